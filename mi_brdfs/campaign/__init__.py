"""
The validation campaign: every check of :mod:`mi_brdfs.checks` on every plugin over a parameter
grid with its extremes, the side-by-side comparisons with Mitsuba's built-ins, and the lecture
notes' claims checked numerically; written as ``validation/REPORT.md`` with its figures.

Run by ``mi-brdfs validate [--quick]`` and ``make validate``. Each section is a function that
takes a :class:`~mi_brdfs.campaign.core.Context` and returns a
:class:`~mi_brdfs.campaign.core.Section` (summary rows, Markdown, figures).
"""

from .core import Context, Section, run


def sections() -> list:
    """The report's sections, in order."""
    from . import (anisotropy, ashikhmin, claims, cooktorrance, earth, extremes, fits, he, hk,
                   lafortune, lambert, measured, multiscatter, orennayar, phong, transmission,
                   ward)
    return [lambert.section, phong.section, cooktorrance.section, anisotropy.section,
            transmission.section, multiscatter.section, ward.section, orennayar.section,
            lafortune.section, ashikhmin.section, fits.section, measured.section,
            he.section, earth.section, hk.section, claims.section, extremes.section]


__all__ = ["Context", "Section", "run", "sections"]

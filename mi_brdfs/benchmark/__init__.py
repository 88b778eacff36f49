"""
The speed-vs-accuracy benchmark: every plugin and sampling choice measured against
the built-ins and each other, as ratios and curves measured side by side in one run (medians of
interleaved repeats), written as ``validation/SPEED_ACCURACY.md`` with its plots.

Run by ``mi-brdfs bench [--quick]`` and ``make bench``. Benchmarks assert nothing: the targets
are reported met or missed in the report's summary.
"""


def sections() -> list:
    """The report's sections, in order."""
    from . import (backends, earth, error_time, explore, he, hk, measured, models, precision,
                   strategies, thinfilm, user_scene)
    return [backends.section, error_time.section, strategies.section, measured.section,
            he.section, earth.section, hk.section, thinfilm.section, models.section,
            precision.section, user_scene.section, explore.section]

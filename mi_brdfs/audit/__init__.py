"""
``mi-brdfs audit``: every BSDF plugin Mitsuba ships (and the package's own) over a grid of
configurations (:mod:`.grid`), through the battery of checks and Mitsuba's own χ² harness in
worker processes with a per-case cache (:mod:`.run`), each failure given a verdict with its proof
(:mod:`.triage`, :mod:`.findings`), written to ``MITSUBA_AUDIT.md`` and
``audit/findings.json`` (:mod:`.report`).
"""

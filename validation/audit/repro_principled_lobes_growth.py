"""
Reproducer: ``principled`` and ``principledthin`` append their lobes again at every
``parameters_changed()`` (Mitsuba 3.9.1, principled.cpp line 325 and principledthin.cpp line
257 call ``initialize_lobes()``, which ``push_back``s into ``m_components`` without clearing
it), so ``component_count()`` grows with each parameter update, e.g. after every step of an
optimisation that updates the BSDF's parameters with ``mi.traverse(...).update()``.

No check of the audit's battery updates parameters, so no audit record shows this; it is kept
apart from repro_principled_component_slots.py and repro_principled_context.py because its
cause (a missing ``m_components.clear()``) is different.

Uses only mitsuba, drjit and numpy. Exits 1 while the defect is present, 0 once fixed.
"""

import sys

import mitsuba as mi

mi.set_variant("llvm_ad_rgb")


def main():
    bad = False
    for name in ("principled", "principledthin"):
        bsdf = mi.load_dict({"type": name})
        params = mi.traverse(bsdf)
        counts = [bsdf.component_count()]
        for _ in range(2):
            params["roughness.value"] = 0.5      # the same value: only the update matters
            params.update()
            counts.append(bsdf.component_count())
        grows = counts[-1] != counts[0]
        bad |= grows
        print(f"{name}: component_count() after 0, 1, 2 updates: {counts}"
              f"{'   <-- defect' if grows else ''}")
    print("DEFECT PRESENT" if bad else "ok")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())

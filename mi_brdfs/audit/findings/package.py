"""Triage of the package's own plugins."""

from ..triage import Finding

FINDINGS = [
    Finding(
        bsdf="cooktorrance", check=r"^energy$", configs=r"diffuse base", verdict="model-property",
        summary=(
            "cooktorrance with the diffuse base ρd = 0.5 beside its default specular lobe "
            "(ks = 1, copper) reflects E(θ) = 1.45 (1.456 at 89°): the model adds the two lobes, "
            "as Cook & Torrance (1982, §3: R = s·Rs + d·Rd) do, leaving s + d = 1 to the user, "
            "and this configuration has ks + ρd = 1.5. The quadrature of eval() with the base "
            "minus without it is 0.50000 at 0° and at 89° (additivity to 2e-8), and copper's "
            "specular lobe alone reflects ≤ 0.957; with ks = ρd = 0.5 the maximum is 0.978 "
            "(check_energy passes). The plugin's docstring states that ρd + E_spec ≤ 1 is up to "
            "the user; the audit keeps this configuration to show that the check catches it."),
    ),
]

"""
The fits section's comparison with Ngan, Durand & Matusik (2005) says what agrees and what does
not from the residuals it is given (no fit here: made-up residuals; the section itself runs in
``mi-brdfs validate --only fits``).
"""

from mi_brdfs.campaign.fits import LECTURE, STYLES, models_for, ngan_comparison, ranking

#: Two targets: on "agrees" the ranking is Ngan et al.'s (Ashikhmin-Shirley and Cook-Torrance
#: first, Ward and Blinn-Phong behind, Lafortune worse at grazing pairs than elsewhere); on
#: "differs" Ward leads and Lafortune is no worse at grazing pairs than the others.
RESIDUALS = {"agrees": {"phong": 0.9, "ward": 0.6, "cooktorrance": 0.3, "ashikhmin": 0.35,
                        "lafortune": 0.5},
             "differs": {"phong": 0.6, "ward": 0.1, "cooktorrance": 0.2, "ashikhmin": 0.18,
                         "lafortune": 0.5}}
GRAZING = {"agrees": {"phong": 1.0, "ward": 0.7, "cooktorrance": 0.33, "ashikhmin": 0.4,
                      "lafortune": 1.0},
           "differs": {"phong": 0.9, "ward": 0.3, "cooktorrance": 0.4, "ashikhmin": 0.36,
                       "lafortune": 0.3}}


def test01_ngan_comparison_from_the_values():
    text = ngan_comparison(RESIDUALS, GRAZING)
    lines = {line.split(":")[0]: line for line in text.splitlines() if line.startswith("* ")}
    assert len(lines) == 4, text
    best, worse, above, share = lines.values()
    assert "agrees on agrees (ranks of 5: ashikhmin 2, cooktorrance 1); not on differs " \
           "(ranks of 5: ashikhmin 2, cooktorrance 3; ward and ashikhmin first)" in best
    assert "agrees on agrees (ward 4, phong 5); not on differs (ward 1, phong 5)" in worse
    assert "agrees on agrees (lafortune 1, ashikhmin 0.4, cooktorrance 0.33); not on " \
           "differs (lafortune 0.3," in above
    assert "agrees on agrees (lafortune 2.00×, ashikhmin 1.14×, cooktorrance 1.10×); not on " \
           "differs (lafortune 0.60×" in share
    assert ranking(RESIDUALS["differs"]) == ["ward", "ashikhmin", "cooktorrance", "lafortune",
                                             "phong"]


def test02_every_lecture_model_is_fitted_to_every_target():
    for target in ("roughconductor material=Au alpha=0.2", "roughplastic"):
        assert [name for name, _, _ in models_for(target)] == list(STYLES)
    assert list(STYLES) == ["phong", "ward", "cooktorrance", "ashikhmin", "lafortune", "he"]
    assert LECTURE == ("phong", "ward", "cooktorrance", "ashikhmin", "lafortune")

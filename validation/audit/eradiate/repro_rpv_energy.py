"""
rpv of eradiate-mitsuba 0.5.0 with its defaults (rho_0 = 0.1, k = 0.1, g = 0): the white
furnace at θi = 89° reflects about 21 times the light it receives. The Minnaert factor of
Rahman, Pinty & Verstraete (1993, https://doi.org/10.1029/93JD02072, eq. 3),
(cosθi cosθo (cosθi + cosθo))^(k-1), grows without bound towards grazing incidence for k < 1,
so the model itself creates energy there: the same formula in float64 (below, from the paper)
gives the same albedo. A property of the model.

Run: .venv-eradiate/bin/python validation/audit/eradiate/repro_rpv_energy.py
Exits 1 while the albedo at 89° exceeds 1.
"""
import sys

import drjit as dr
import mitsuba as mi
import numpy as np

mi.set_variant("llvm_ad_rgb")
RHO_0, K, G = 0.1, 0.1, 0.0
THETA_I = np.radians(89.0)
N = 2_000_000


def model_f(mu_i, mu_o, cos_phi):
    """RPV in float64, ρc = ρ0, φ the relative azimuth (0: backscatter)."""
    s_i, s_o = np.sqrt(1 - mu_i ** 2), np.sqrt(1 - mu_o ** 2)
    cos_big = mu_i * mu_o + s_i * s_o * cos_phi  # the phase angle's cosine (wi·wo)
    f_hg = (1 - G ** 2) / (1 + G ** 2 + 2 * G * cos_big) ** 1.5
    t_i, t_o = s_i / mu_i, s_o / mu_o
    big_g = np.sqrt(np.maximum(t_i ** 2 + t_o ** 2 - 2 * t_i * t_o * cos_phi, 0))
    h = 1 + (1 - RHO_0) / (1 + big_g)
    return RHO_0 / np.pi * (mu_i * mu_o * (mu_i + mu_o)) ** (K - 1) * f_hg * h


rng = np.random.default_rng(1)
bsdf = mi.load_dict({"type": "rpv"})
si = dr.zeros(mi.SurfaceInteraction3f, N)
si.wi = mi.Vector3f(float(np.sin(THETA_I)), 0.0, float(np.cos(THETA_I)))
si.sh_frame = mi.Frame3f(mi.Vector3f(0, 0, 1))
u1, u2 = rng.random(N), rng.random(N)
_, weight = bsdf.sample(mi.BSDFContext(), si, mi.Float(rng.random(N)), mi.Point2f(u1, u2))
w = np.array(weight)[0]
albedo, err = w.mean(), w.std() / np.sqrt(N)
print(f"Eradiate rpv, white furnace at θi = 89°: albedo {albedo:.3f} ± {err:.3f}")

# the model in float64: cosine-weighted Monte Carlo, albedo = E[π f]
r, phi = np.sqrt(u1), 2 * np.pi * u2
mu_o = np.sqrt(np.maximum(1 - r ** 2, 1e-300))
value = np.pi * model_f(np.cos(THETA_I), mu_o, np.cos(phi))
print(f"float64 model (Rahman et al. 1993): albedo {value.mean():.3f} ± "
      f"{value.std() / np.sqrt(N):.3f}")
sys.exit(1 if albedo > 1 else 0)

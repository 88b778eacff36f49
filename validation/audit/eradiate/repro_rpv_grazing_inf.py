"""
rpv of eradiate-mitsuba 0.5.0 returns Inf at grazing backscatter (wi = wo at cosθ = 6.1e-17,
the float64 cos 90° the checks use): rpv.cpp (v0.5.0) lines 160-161 compute the Minnaert factor
dr::pow(cos_theta_i * cos_theta_o * (cos_theta_i + cos_theta_o), k - 1.f); the product,
4.6e-49, underflows to 0 in float32 and pow(0, k - 1 < 0) is Inf. The model's value there is
finite: eval = f cosθo from the same formula in float64 (below) is 1.7e-8 for k = 0.8 and 1.2e26
for k = 0.1 (the Minnaert factor diverges towards grazing for k < 1: a property of the model,
repro_rpv_energy.py). Inf where the model is finite is the implementation's.

Run: .venv-eradiate/bin/python validation/audit/eradiate/repro_rpv_grazing_inf.py
Exits 1 while Eradiate's rpv returns a non-finite eval there.
"""
import sys

import drjit as dr
import mitsuba as mi
import numpy as np

mi.set_variant("llvm_ad_rgb")
MU = float(np.cos(np.pi / 2))  # 6.123e-17
SIN = float(np.sqrt(1 - MU * MU))
bad = False
for k in (0.1, 0.8):
    bsdf = mi.load_dict({"type": "rpv", "k": k})
    si = dr.zeros(mi.SurfaceInteraction3f, 2)
    si.wi = mi.Vector3f(SIN, 0.0, MU)
    si.sh_frame = mi.Frame3f(mi.Vector3f(0, 0, 1))
    value = np.array(bsdf.eval(mi.BSDFContext(), si, mi.Vector3f(SIN, 0.0, MU)))[0, 0]
    # float64, wi = wo: F = 1 (g = 0), G = 0, H = 1 + (1 - ρc)/(1 + 0) = 1.9 (ρc = ρ0 = 0.1)
    model = 0.1 / np.pi * (MU * MU * 2 * MU) ** (k - 1) * 1.9 * MU
    print(f"k = {k}: Eradiate eval = {value}, float64 model eval = {model:.3g}, "
          f"float32 product = {np.float32(MU) * np.float32(MU) * np.float32(2 * MU)}")
    bad |= not np.isfinite(value)
sys.exit(1 if bad else 0)

"""
The call structure of selectbsdf, in Python and in any Mitsuba 3 build: a symbolic call
(dr.dispatch) over BSDF pointers whose callable, for one instance (c, standing for the
selector), dispatches a call again over BSDF pointers, one level deep (every instance is
traced in each, as in a symbolic call). Forward-mode differentiation aborts the
process ("unknown variable") when the inner call runs the same function as the outer one, and
works when it runs another function; reverse mode works either way. Runs under Mitsuba 3.7.1
(Dr.Jit 1.2.0, eradiate-mitsuba 0.5.0) and 3.9.1 (Dr.Jit 1.5.0) alike: a newer Mitsuba does
not remove the abort that repro_selectbsdf_forward_ad.py shows.

Run: PYTHON validation/audit/eradiate/drjit_nested_call_forward.py
Exits 1 while forward mode aborts on the self-recursive call (in a child process).
"""
import subprocess
import sys

CHILD = r'''
import sys
import drjit as dr, mitsuba as mi
mi.set_variant("llvm_ad_rgb")
inner_name, mode = sys.argv[1], sys.argv[2]
a = mi.load_dict({"type": "diffuse"})
b = mi.load_dict({"type": "roughconductor", "alpha": 0.3})
c = mi.load_dict({"type": "diffuse", "reflectance": 0.1})
ctx = mi.BSDFContext()

def other(self, si, wo):
    return self.eval(ctx, si, wo)

depth = [0]

def outer(self, si, wo):
    if self is c and depth[0] == 0:   # as selectbsdf: gather a nested BSDF, call it
        depth[0] += 1                 # (one level: the inner call evaluates c plainly)
        try:
            nested = dr.gather(mi.BSDFPtr, mi.BSDFPtr(a), mi.UInt32(0))
            return dr.dispatch(nested, outer if inner_name == "same" else other, si, wo)
        finally:
            depth[0] -= 1
    return self.eval(ctx, si, wo)

t = mi.Float(0.0)
dr.enable_grad(t)
params = mi.traverse(a)
params["reflectance.value"] = params["reflectance.value"] + t
params.update()
si = dr.zeros(mi.SurfaceInteraction3f, 4)
si.wi = mi.Vector3f(0, 0, 1)
si.sh_frame = mi.Frame3f(mi.Vector3f(0, 0, 1))
ptr = dr.select(mi.Bool([True, False, True, False]), mi.BSDFPtr(c), mi.BSDFPtr(b))
value = dr.dispatch(ptr, outer, si, mi.Vector3f(0.3, 0, 0.954))
if mode == "backward":
    dr.backward(dr.sum(value))
    print("d/dρ =", dr.grad(t)[0])
else:
    dr.forward(t)
    print("d eval/dρ =", dr.grad(value)[0, 0])
'''

import mitsuba as mi  # noqa: E402 (only for the version line)
print(f"Mitsuba {mi.MI_VERSION}")
bad = False
for inner_name in ("other", "same"):
    for mode in ("backward", "forward"):
        run = subprocess.run([sys.executable, "-c", CHILD, inner_name, mode], capture_output=True,
                             text=True)
        fatal = [line for line in run.stderr.splitlines() if "unknown variable" in line]
        print(f"inner call runs the {inner_name} function, {mode}: exit {run.returncode}; " +
              (fatal[0].strip() if fatal else (run.stdout + run.stderr).strip().splitlines()[-1]))
        bad |= bool(fatal)
sys.exit(1 if bad else 0)

"""
selectbsdf of eradiate-mitsuba 0.5.0 makes forward-mode differentiation abort the process with
Dr.Jit's fatal "jit_var(rN): unknown variable!", in every call through a BSDF pointer once a
selectbsdf exists: its own eval, and any other BSDF's (a prb render's dr.forward included).
Primal evaluation, reverse mode (dr.backward) and non-symbolic calls
(JitFlag.SymbolicCalls = False) work.

selectbsdf.cpp (v0.5.0) lines 104-106 (eval; sample and pdf alike at 95-97, 113-115) gather a
nested BSDF pointer and call it: a symbolic call over the BSDF registry from inside a BSDF's
method. A symbolic call traces every registered instance of its domain (Dr.Jit 1.2.0, the
fork's ext/drjit: src/extra/call.cpp, ad_call_symbolic, lines 302-310), the selectbsdf
itself among them, so BSDF::eval is traced inside a call of BSDF::eval (Dr.Jit-Core limits
that recursion: jit_record_begin, src/api.cpp lines 187-189; ad_call_symbolic returns early,
call.cpp lines 283-285). It is the forward-mode replay of such a call (CallOp::forward,
call.cpp line 616, re-running each callable in forward_cb, line 704) that aborts:
drjit_nested_call_forward.py models it in Python, where a call nested in a call of the same
function aborts in forward mode and one of another function does not, under Dr.Jit 1.2.0
and 1.5.0 (Mitsuba 3.9.1, which has no selectbsdf) alike.

The abort kills the interpreter, so the calls run in a child process.

Run: .venv-eradiate/bin/python validation/audit/eradiate/repro_selectbsdf_forward_ad.py
Exits 1 while forward mode aborts with a selectbsdf present.
"""
import subprocess
import sys

CHILD = r'''
import sys
import drjit as dr, mitsuba as mi
mi.set_variant("llvm_ad_rgb")
mode = sys.argv[1]
a = mi.load_dict({"type": "diffuse"})
b = mi.load_dict({"type": "roughconductor", "alpha": 0.3})
if mode != "no selectbsdf":
    sel = mi.load_dict({"type": "selectbsdf", "indices": 0.0, "a": a, "b": b})
t = mi.Float(0.0)
dr.enable_grad(t)
params = mi.traverse(a)
params["reflectance.value"] = params["reflectance.value"] + t
params.update()
si = dr.zeros(mi.SurfaceInteraction3f, 4)
si.wi = mi.Vector3f(0, 0, 1)
si.sh_frame = mi.Frame3f(mi.Vector3f(0, 0, 1))
wo = mi.Vector3f(0.3, 0, 0.954)
if mode.startswith("selectbsdf"):
    value = sel.eval(mi.BSDFContext(), si, wo)
else:   # a call through a pointer to the diffuse BSDF alone
    value = dr.gather(mi.BSDFPtr, mi.BSDFPtr(a), mi.UInt32(0)).eval(mi.BSDFContext(), si, wo)
if mode.endswith("backward"):
    dr.backward(dr.sum(value))
    print("d/dρ =", dr.grad(t)[0])
else:
    dr.forward(t)
    print("d eval/dρ =", dr.grad(value)[0, 0])
'''

bad = False
for mode in ("no selectbsdf", "selectbsdf eval, backward", "selectbsdf eval",
             "diffuse through a pointer, a selectbsdf loaded"):
    run = subprocess.run([sys.executable, "-c", CHILD, mode], capture_output=True, text=True)
    fatal = [line for line in run.stderr.splitlines() if "unknown variable" in line]
    print(f"{mode}: exit {run.returncode}; " + (fatal[0].strip() if fatal else
                                                run.stdout.strip().splitlines()[-1]))
    bad |= bool(fatal)
sys.exit(1 if bad else 0)

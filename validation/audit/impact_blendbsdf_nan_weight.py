"""
Render impact of the blendbsdf NaN-weight defect (repro_blendbsdf_nan_weight.py): a one-sided
``blendbsdf(weight 0.3, diffuse, roughconductor α = 0.2)`` rectangle in a constant environment,
seen from the front and from behind (where the nested roughconductor's samples fail and the
blend's weights are NaN), with every shipped integrator that samples BSDFs, and the ``prb``
gradient with respect to the blend weight.

Mitsuba 3.9.1, llvm_ad_rgb: no NaN pixel with path, direct, volpath, prb or ptracer, and a finite
gradient (0 from behind). The integrators end a path whose throughput is NaN, because
``throughput_max != 0`` is an ordered comparison.
"""

import drjit as dr
import mitsuba as mi
import numpy as np

BLEND = {"type": "blendbsdf", "weight": 0.3, "a": {"type": "diffuse"},
         "b": {"type": "roughconductor", "alpha": 0.2}}


def scene(z, integrator):
    return mi.load_dict({
        "type": "scene", "integrator": {"type": integrator},
        "sensor": {"type": "perspective", "fov": 30,
                   "to_world": mi.ScalarTransform4f().look_at(origin=[0, 0, z], target=[0, 0, 0],
                                                              up=[0, 1, 0]),
                   "film": {"type": "hdrfilm", "width": 16, "height": 16,
                            "rfilter": {"type": "box"}},
                   "sampler": {"type": "independent", "sample_count": 16}},
        "emitter": {"type": "constant", "radiance": 1.0},
        "plane": {"type": "rectangle", "bsdf": BLEND}})   # normal +z


def main():
    mi.set_variant("llvm_ad_rgb")
    for integrator in ("path", "direct", "volpath", "prb", "ptracer"):
        for z, side in ((3, "front"), (-3, "behind")):
            img = np.array(mi.render(scene(z, integrator), spp=16))
            print(f"{integrator:8s} {side:6s}: NaN pixels {int(np.isnan(img).any(-1).sum())} of "
                  f"{img.shape[0] * img.shape[1]}, mean {np.nanmean(img):.4f}")
    for z, side in ((3, "front"), (-3, "behind")):
        sc = scene(z, "prb")
        params = mi.traverse(sc)
        key = "plane.bsdf.weight.value"
        dr.enable_grad(params[key])
        params.update()
        img = mi.render(sc, params, spp=16)
        dr.backward(dr.mean(img, axis=None), flags=dr.ADFlag.Default | dr.ADFlag.AllowNoGrad)
        print(f"prb gradient d(mean image)/d(weight), {side}: {dr.grad(params[key])}")


if __name__ == "__main__":
    main()

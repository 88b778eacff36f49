"""
The explorer's progressively rendered sphere: one small scene per BSDF, a unit sphere seen by a
perspective camera that it fills, under a movable light and a dim constant environment (so the
side turned from the light is not black), rendered by Mitsuba's path tracer in the current (JIT)
variant, a pass at a time, and accumulated into a running mean (:class:`Spheres`).

Each scene holds the very BSDF object it is given, so a parameter set through that BSDF's
``mi.traverse`` shows in the next pass without a new scene; the light moves through the
scene's ``mi.traverse``. Neither re-traces: the values are inputs of the kernels compiled for
the first pass, not part of their code (Mitsuba's documentation, "Scene parameters"), and the
pass's seed is an opaque ``mi.UInt32`` too; that holds for a BSDF whose plugin keeps its
parameters opaque (a plugin that bakes a value into its code compiles anew for each value). A pass renders :data:`PASS_SAMPLES` samples
over all the spheres by default.

The light, at (θ, φ) relative to the view (θ = 0: from the camera; φ = 0: from the right of
the image, φ = 90°: from above), is one of :data:`LIGHTS`:

- ``"directional"``: a distant light of irradiance π, BRDF Explorer's "lit sphere": a white
  Lambertian sphere shows cos θ at each point, plus the environment's ``ambient``;
- ``"point"``: a point light at :data:`POINT_DISTANCE` radii from the centre, of irradiance π
  at the centre's distance;
- ``"envmap"``: a lat-long environment of radiance ``ambient`` with a sun of
  :data:`SUN_RADIUS_DEG` whose irradiance is π (a soft directional light), rotated.

All BSDFs render each pass with the same seed (common random numbers): two equal BSDFs give
equal images, and a difference between two BSDFs is not hidden by noise. A :meth:`reset`
starts the seeds anew, so the first pass after a parameter change has the noise of the one
before it and only the change shows.

The difference image is the signed difference of the mean of the channels (BSDF i − BSDF 0), in
the blue-white-red map ``RdBu_r`` of ``mi-brdfs compare``'s figure, saturating at
:data:`DIFFERENCE_SCALE` of BSDF 0's brightest (99.5th percentile) value; FLIP is NVIDIA's
perceptual error (Andersson et al. 2020, "FLIP: A Difference Evaluator for Alternating
Images", https://research.nvidia.com/publication/2020-07_flip) of the previews as the page
shows them (LDR mode, on the sRGB images: HDR-FLIP brackets exposures and takes 0.1 to 2 s
for a 64 × 64 pair, LDR-FLIP about 10 ms).
"""

from __future__ import annotations

import math

import numpy as np

from ..errors import MiBrdfsError
from ..imageio import to_srgb8

#: The lights :class:`Spheres` takes.
LIGHTS = ("directional", "point", "envmap")

#: Samples (pixels × spp) of a pass of all the spheres together, by default: 32 spp for one
#: 64² sphere, 8 for four, so that the first pass after a change stays well within 300 ms on
#: two cores (a pass costs about 10 ms per sphere plus 0.5 ms per 64² × 1 spp).
PASS_SAMPLES = 1 << 17

#: Distance of the camera from the sphere's centre, in radii.
CAMERA_DISTANCE = 4.0

#: Distance of the point light from the sphere's centre, in radii.
POINT_DISTANCE = 5.0

#: Angular radius of the envmap's sun.
SUN_RADIUS_DEG = 5.0

#: The difference image saturates at this fraction of BSDF 0's brightest value.
DIFFERENCE_SCALE = 0.25


def camera_fov(distance: float = CAMERA_DISTANCE, margin: float = 1.04) -> float:
    """Horizontal field of view (degrees) in which the unit sphere seen from ``distance``
    fills the frame, with ``margin``."""
    return 2.0 * math.degrees(math.asin(1.0 / distance)) * margin


def light_direction(theta_deg: float, phi_deg: float) -> np.ndarray:
    """Unit direction towards the light at (θ, φ) relative to the view, in the world frame
    (= the camera's: x to the right of the image, y up, z towards the camera)."""
    t, p = math.radians(theta_deg), math.radians(phi_deg)
    return np.array([math.sin(t) * math.cos(p), math.sin(t) * math.sin(p), math.cos(t)])


def _frame_to(direction):
    """A ``ScalarAffineTransform4f`` whose local +z goes to ``direction``."""
    import mitsuba as mi

    d = [float(v) for v in direction]
    up = [0.0, 1.0, 0.0] if abs(d[1]) < 0.99 else [0.0, 0.0, 1.0]
    return mi.ScalarAffineTransform4f().look_at(origin=[0, 0, 0], target=d, up=up)


def _sun_sky(ambient: float, height: int = 128) -> np.ndarray:
    """The envmap's lat-long image (height × 2·height × 3): radiance ``ambient`` and a sun
    cap of :data:`SUN_RADIUS_DEG` around the local +y pole (the top rows) whose irradiance
    at normal incidence is π, i.e. radiance π / (its solid angle)."""
    radius = math.radians(SUN_RADIUS_DEG)
    theta = (np.arange(height) + 0.5) / height * math.pi  # row centres' polar angles
    rows = theta < radius
    # the rows' real solid angle, so that the discretised sun has the intended power
    edges = np.arange(height + 1) / height * math.pi
    solid = 2.0 * math.pi * (np.cos(edges[:-1]) - np.cos(edges[1:]))
    sun = math.pi / float(np.sum(solid[rows] * np.cos(theta[rows])))
    image = np.full((height, 2 * height, 3), ambient, np.float32)
    image[rows] = sun + ambient
    return image


def _light_dict(light: str, ambient: float) -> dict:
    """The scene's light (key ``light``; its direction set later by ``set_light``)."""
    import mitsuba as mi

    if light == "directional":
        return {"type": "directional", "irradiance": math.pi}
    if light == "point":
        return {"type": "point", "position": [0.0, 0.0, POINT_DISTANCE],
                "intensity": math.pi * POINT_DISTANCE ** 2}
    return {"type": "envmap", "bitmap": mi.Bitmap(_sun_sky(ambient))}


def scene_dict(bsdf, res: int, light: str, ambient: float, max_depth: int) -> dict:
    """The ``mi.load_dict`` dict of one sphere's scene, holding ``bsdf`` (the object itself)."""
    import mitsuba as mi

    camera = mi.ScalarTransform4f().look_at(origin=[0, 0, CAMERA_DISTANCE], target=[0, 0, 0],
                                            up=[0, 1, 0])
    scene = {
        "type": "scene",
        "integrator": {"type": "path", "max_depth": max_depth},
        "sensor": {"type": "perspective", "fov": camera_fov(), "to_world": camera,
                   "film": {"type": "hdrfilm", "width": res, "height": res,
                            "pixel_format": "rgb", "rfilter": {"type": "box"}},
                   "sampler": {"type": "independent"}},
        "sphere": {"type": "sphere", "bsdf": bsdf},
        "light": _light_dict(light, ambient),
    }
    if light != "envmap":
        # sampled rarely by the emitter sampling (found by the BSDF's, MIS): the light's
        # samples are not wasted on it
        scene["ambient"] = {"type": "constant", "radiance": ambient, "sampling_weight": 0.1}
    return scene


def _check_spp(spp) -> None:
    """One line for samples per pixel that are no integer ≥ 1 (None: the default)."""
    if spp is not None and not (isinstance(spp, int) and spp >= 1):
        raise MiBrdfsError(f"explore: sphere spp {spp!r} must be an integer ≥ 1")


def _check(res: int, light: str, ambient: float, spp) -> None:
    """One line naming the option and what is allowed, for a bad argument of Spheres."""
    if light not in LIGHTS:
        raise MiBrdfsError(f"explore: sphere light {light!r} is unknown (one of: "
                           f"{', '.join(LIGHTS)})")
    if not (isinstance(res, int) and 1 <= res <= 4096):
        raise MiBrdfsError(f"explore: sphere resolution {res!r} must be an integer in [1, 4096]")
    if not (math.isfinite(ambient) and ambient >= 0):
        raise MiBrdfsError(f"explore: sphere ambient {ambient!r} must be a finite number ≥ 0")
    _check_spp(spp)


class Spheres:
    """
    The progressively rendered spheres of up to four BSDFs.

    Parameter ``bsdfs``: ``mi.BSDF`` objects (kept, not copied: a change through their
    ``mi.traverse`` shows after :meth:`reset`) or specs that :func:`mi_brdfs.bsdfspec.load_bsdf`
    takes. ``res``: the images' width and height in pixels. ``light``: one of :data:`LIGHTS`.
    ``theta``, ``phi``: the light's direction in degrees (see :meth:`set_light`). ``ambient``:
    the environment's radiance. ``spp``: samples per pixel of a pass (default: about
    :data:`PASS_SAMPLES` over all the spheres, at least 1). ``max_depth``: the path
    tracer's (2 is exact for a reflecting sphere; more for one that transmits). ``seed``: base
    seed of the passes. :meth:`from_scene`: a scene file's view instead of the sphere.
    """

    def __init__(self, bsdfs, res: int = 64, light: str = "directional", theta: float = 45.0,
                 phi: float = 30.0, ambient: float = 0.05, spp: int | None = None,
                 max_depth: int = 8, seed: int = 0):
        import mitsuba as mi

        from ..bsdfspec import load_bsdf

        bsdfs = [load_bsdf(b) for b in bsdfs]
        _check(res, light, ambient, spp)
        self._scene = (res, light, ambient, max_depth)
        scenes = [mi.load_dict(scene_dict(b, *self._scene)) for b in bsdfs]
        self._start(bsdfs, scenes, light, spp, seed)
        self.set_light(theta, phi)

    def replace(self, i: int, bsdf) -> None:
        """Sphere ``i`` with another BSDF object (a switch or a fit made a new plugin object:
        its scene is made anew, under the light as it is), and start accumulating anew."""
        import mitsuba as mi

        from ..bsdfspec import load_bsdf
        from ..scenes import load_scene

        self.bsdfs[i] = load_bsdf(bsdf)
        if self.light is None:
            path, defines, bsdf_id = self._scene
            self.scenes[i] = load_scene(path, defines, bsdfs={bsdf_id: self.bsdfs[i]})
        else:
            self.scenes[i] = mi.load_dict(scene_dict(self.bsdfs[i], *self._scene))
        self.params[i] = mi.traverse(self.scenes[i])
        if self.light is not None:
            self.set_light(self.theta, self.phi)
        self.reset()

    @classmethod
    def from_scene(cls, path, bsdfs, bsdf_id: str, defines: dict | None = None,
                   spp: int | None = None, seed: int = 0) -> Spheres:
        """The spheres' views of a scene file instead (a path or a bundled scene's name, with
        ``<default>`` overrides ``defines``): one scene per BSDF, whose ``<bsdf id=bsdf_id>``
        is that very BSDF object (:func:`mi_brdfs.scenes.load_scene`), at the scene's film
        size, under the scene's own lights (:meth:`set_light` refuses)."""
        from ..bsdfspec import load_bsdf
        from ..scenes import load_scene

        bsdfs = [load_bsdf(b) for b in bsdfs]
        scenes = [load_scene(path, defines, bsdfs={bsdf_id: b}) for b in bsdfs]
        _check_spp(spp)
        self = cls.__new__(cls)
        self._scene = (path, defines, bsdf_id)
        self._start(bsdfs, scenes, None, spp, seed)
        self.reset()
        return self

    def _start(self, bsdfs, scenes, light, spp, seed) -> None:
        """The state common to both constructors (``light``: None for a scene file)."""
        import mitsuba as mi

        if not bsdfs:
            raise MiBrdfsError("explore: the sphere needs at least one BSDF")
        self.bsdfs, self.scenes, self.light, self.seed = bsdfs, scenes, light, seed
        self.params = [mi.traverse(s) for s in scenes]
        width, height = (int(v) for v in scenes[0].sensors()[0].film().crop_size())
        #: the images' (height, width)
        self.shape = (height, width)
        self.res = width
        if spp is None:
            spp = max(1, PASS_SAMPLES // (len(bsdfs) * width * height))
        self.spp = spp
        self.theta = self.phi = None

    def __len__(self) -> int:
        return len(self.bsdfs)

    def set_light(self, theta_deg: float, phi_deg: float) -> None:
        """Move the light to (θ, φ) degrees relative to the view (θ = 0: from the camera,
        φ = 0: from the right, 90°: from above) through each scene's ``mi.traverse``, and
        start accumulating anew."""
        import mitsuba as mi

        if self.light is None:
            raise MiBrdfsError("explore: the lights of a scene file do not move (set_light)")
        theta_deg, phi_deg = float(theta_deg), float(phi_deg)
        if not (math.isfinite(theta_deg) and math.isfinite(phi_deg)):
            raise MiBrdfsError(f"explore: sphere light direction ({theta_deg}, {phi_deg}) "
                               "must be finite angles in degrees")
        towards = light_direction(theta_deg, phi_deg)
        for params in self.params:
            if self.light == "point":
                position = [float(v) for v in POINT_DISTANCE * towards]
                params["light.position"] = mi.Point3f(*position)
            elif self.light == "directional":  # the light travels along its local +z
                params["light.to_world"] = mi.AffineTransform4f(_frame_to(-towards))
            else:  # the sun is at the envmap's local +y: turn +y to +z, then +z to the light
                rotate = mi.ScalarAffineTransform4f().rotate([1, 0, 0], 90.0)
                params["light.to_world"] = mi.AffineTransform4f(_frame_to(towards) @ rotate)
            params.update()
        self.theta, self.phi = theta_deg, phi_deg
        self.reset()

    def reset(self) -> None:
        """Start accumulating anew (after a parameter change or a light move): the next
        :meth:`step` is pass 1 again, with the seeds of the first pass."""
        self.passes = 0
        self._spp = 0  # samples per pixel accumulated
        self._sums = [None] * len(self.bsdfs)

    def step(self, spp: int | None = None) -> int:
        """Render one more pass of ``spp`` (default ``self.spp``) samples per pixel for every
        BSDF, all with the same new seed, and add it to the running means (weighted by spp);
        the passes so far."""
        import drjit as dr
        import mitsuba as mi

        from ..render_pool import pass_seed

        _check_spp(spp)
        spp = self.spp if spp is None else spp
        seed = dr.opaque(mi.UInt32, pass_seed(self.seed, self.passes))
        images = [mi.render(scene, seed=seed, spp=spp) for scene in self.scenes]
        for i, image in enumerate(images):
            image = np.asarray(image, np.float64)[:, :, :3] * spp
            self._sums[i] = image if self._sums[i] is None else self._sums[i] + image
        self.passes += 1
        self._spp += spp
        return self.passes

    def linear(self, i: int) -> np.ndarray:
        """BSDF ``i``'s running mean: linear radiance, float32 (height, width, 3); black
        before the first pass."""
        if self._sums[i] is None:
            return np.zeros(self.shape + (3,), np.float32)
        return (self._sums[i] / self._spp).astype(np.float32)

    def image(self, i: int) -> np.ndarray:
        """BSDF ``i``'s preview: the running mean clipped to [0, 1] and sRGB-encoded, uint8
        (height, width, 3)."""
        return to_srgb8(self.linear(i))

    def difference(self, i: int) -> np.ndarray:
        """The signed difference BSDF ``i`` − BSDF 0 of the means of the channels in the map
        ``RdBu_r`` (blue: darker than BSDF 0, white: equal, red: brighter), saturating at
        ±:data:`DIFFERENCE_SCALE` of BSDF 0's 99.5th percentile: uint8 (height, width, 3)."""
        import matplotlib

        reference = self.linear(0).mean(axis=2)
        diff = self.linear(i).mean(axis=2) - reference
        scale = DIFFERENCE_SCALE * max(float(np.percentile(reference, 99.5)), 1e-6)
        shown = np.clip(0.5 + 0.5 * diff / scale, 0.0, 1.0)
        rgba = matplotlib.colormaps["RdBu_r"](shown)
        return np.round(rgba[:, :, :3] * 255.0).astype(np.uint8)

    def flip(self, i: int) -> float | None:
        """Mean LDR-FLIP of BSDF ``i``'s preview (:meth:`image`) against BSDF 0's (0:
        equal); None without the ``flip-evaluator`` package."""
        try:
            import flip_evaluator as flip
        except ImportError:
            return None
        reference, test = (np.ascontiguousarray(self.image(k), np.float32) / 255.0
                           for k in (0, i))
        return float(flip.evaluate(reference, test, "LDR", applyMagma=False)[1])

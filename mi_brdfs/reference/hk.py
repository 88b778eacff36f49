r"""
Hanrahan & Krueger's layer in float64 (Hanrahan & Krueger 1993, "Reflection from Layered Surfaces
due to Subsurface Scattering", SIGGRAPH, §3-4): a slab of thickness d of a homogeneous medium
(σs, σa, σt = σs + σa, albedo a = σs/σt, optical depth τ = σt d, Henyey-Greenstein phase g)
under a smooth interface of relative index η, over nothing (a free-standing slab: the same
interface below, light leaves through the back) or over a Lambertian base of reflectance ρ in
contact with the medium.

Directions are (n, 3) unit vectors in the local frame (normal +z), both pointing away from the
surface; μ = |cosθ| outside, μ' = √(1 − (1 − μ²)/η²) the refracted cosine inside, T(μ) = 1 −
F(μ, η) the interface's Fresnel transmittance. A directional beam refracted into the slab is
attenuated as e^{−σt z/μi'}; integrating the once-scattered light over depth (Chandrasekhar
1960, "Radiative Transfer", §46, the slab's first-order solution; Hanrahan & Krueger, eqs. 20-23
with the refracted cosines and the Fresnel transmission of both crossings) gives f, with the
n² law of radiance carried through both crossings (1/η² overall):

.. math::

    f_r &= \frac{a\,p(\cos\Theta)\,T_i T_o}{\eta^2}
           \frac{1 - e^{-\tau(1/\mu_i' + 1/\mu_o')}}{\mu_i' + \mu_o'}, \qquad
    f_t = \frac{a\,p(\cos\Theta)\,T_i T_o}{\eta^2}
           \frac{e^{-\tau/\mu_o'} - e^{-\tau/\mu_i'}}{\mu_o' - \mu_i'}, \\
    f_{base} &= \frac{\rho\,T_i T_o}{\pi\eta^2} e^{-\tau(1/\mu_i' + 1/\mu_o')},

Θ the angle between the refracted incident beam and the refracted outgoing one,
p(cosΘ) = (1 − g²)/(4π (1 + g² − 2g cosΘ)^{3/2}). Beside them the unscattered light: the
mirror reflection F(μi) and, without a base, the beam through the slab, T_i² e^{−τ/μi'} in the
direction −ωi (a parallel slab shifts it, does not turn it). This is the "single" model: paths
with at most one event inside (a scattering or the base), no internal reflection.

:func:`walk` is the whole transport by a float64 Monte Carlo random walk (every order of
scattering, internal Fresnel reflections, the base), tallied by order: the reference for the
orders above the first, each estimate with its standard error.
"""

from __future__ import annotations

import numpy as np


def fresnel(cos_i, eta) -> np.ndarray:
    """Unpolarized Fresnel reflectance of a smooth interface of relative index ``eta`` (η_t/η_i)
    for light at cosine ``cos_i`` ≥ 0 (Born & Wolf §1.5.3); 1 under total reflection."""
    c = np.clip(np.asarray(cos_i, np.float64), 0.0, 1.0)
    s2 = (1.0 - c * c) / (eta * eta)
    ct = np.sqrt(np.maximum(1.0 - s2, 0.0))
    with np.errstate(divide="ignore", invalid="ignore"):
        rs = (c - eta * ct) / (c + eta * ct)
        rp = (eta * c - ct) / (eta * c + ct)
        f = 0.5 * (rs * rs + rp * rp)
    return np.where((s2 >= 1.0) | ~np.isfinite(f), 1.0, f)


def refracted(mu, eta) -> np.ndarray:
    """μ' = √(1 − (1 − μ²)/η²): the cosine inside a medium of index η ≥ 1 of light at μ."""
    mu = np.asarray(mu, np.float64)
    return np.sqrt(np.maximum(1.0 - (1.0 - mu * mu) / (eta * eta), 0.0))


def hg(cos_theta, g) -> np.ndarray:
    """Henyey-Greenstein's phase function, normalised to 1 over the sphere (per steradian)."""
    return (1 - g * g) / (4 * np.pi * (1 + g * g - 2 * g * np.asarray(cos_theta)) ** 1.5)


def sample_hg(d, g, u1, u2) -> np.ndarray:
    """Directions (n, 3) scattered from the unit directions of travel ``d`` by HG(g)."""
    if abs(g) < 1e-6:
        cos_t = 1 - 2 * u1
    else:
        s = (1 - g * g) / (1 - g + 2 * g * u1)
        cos_t = (1 + g * g - s * s) / (2 * g)
    sin_t = np.sqrt(np.maximum(1 - cos_t * cos_t, 0))
    phi = 2 * np.pi * u2
    t1 = np.where(np.abs(d[:, 2:3]) < 0.9, [[0.0, 0.0, 1.0]], [[1.0, 0.0, 0.0]])
    e1 = np.cross(d, t1)
    e1 /= np.linalg.norm(e1, axis=1, keepdims=True)
    e2 = np.cross(d, e1)
    return (cos_t[:, None] * d + (sin_t * np.cos(phi))[:, None] * e1
            + (sin_t * np.sin(phi))[:, None] * e2)


def _channels(x) -> np.ndarray:
    return np.atleast_1d(np.asarray(x, np.float64))


class HK:
    """The layer; ``sigma_s``, ``sigma_a``, ``diffuse_reflectance`` per channel."""

    def __init__(self, sigma_s=0.5, sigma_a=0.5, thickness=1.0, g=0.0, eta=1.0,
                 diffuse_reflectance=0.0):
        self.sigma_s, self.sigma_a = _channels(sigma_s), _channels(sigma_a)
        self.rho = _channels(diffuse_reflectance)
        self.d, self.g, self.eta = float(thickness), float(g), float(eta)
        sigma_t = self.sigma_s + self.sigma_a
        self.tau = sigma_t * self.d
        self.albedo = np.where(sigma_t > 0, self.sigma_s / np.where(sigma_t > 0, sigma_t, 1), 0)
        self.base = bool(np.any(self.rho > 0))

    def _inside(self, w):
        """(μ', T, in-slab direction of w: (x, y)/η and ±μ' with w's side)."""
        mu = np.abs(w[:, 2])
        mup = refracted(mu, self.eta)
        inside = np.stack([w[:, 0] / self.eta, w[:, 1] / self.eta,
                           np.sign(w[:, 2]) * mup], axis=1)
        return mup, 1.0 - fresnel(mu, self.eta), inside

    def brdf(self, wi, wo) -> np.ndarray:
        """f (n, channels) of the "single" model at direction pairs; ωi may be below the
        surface (the slab is symmetric) where there is no base."""
        wi, wo = np.atleast_2d(wi).astype(np.float64), np.atleast_2d(wo).astype(np.float64)
        flip = wi[:, 2:3] < 0
        wi, wo = np.where(flip, -wi, wi), np.where(flip, -wo, wo)
        mi_, ti, di = self._inside(wi)
        mo, to, do = self._inside(wo)
        cos_theta = -np.sum(di * do, axis=1)
        common = (ti * to * hg(cos_theta, self.g) / self.eta ** 2)[:, None] * self.albedo
        mi_, mo = np.maximum(mi_, 1e-300)[:, None], np.maximum(mo, 1e-300)[:, None]
        tau = self.tau[None, :]
        reflect = (wo[:, 2] > 0)[:, None]
        with np.errstate(over="ignore", invalid="ignore", divide="ignore"):
            fr = common * -np.expm1(-tau * (1 / mi_ + 1 / mo)) / (mi_ + mo)
            lo, hi = np.minimum(mi_, mo), np.maximum(mi_, mo)
            y = tau * (1 / lo - 1 / hi)
            ratio = np.where(y > 1e-8, -np.expm1(-y) / np.where(y > 0, y, 1), 1 - y / 2)
            ft = common * np.exp(-tau / hi) * tau / (lo * hi) * ratio
            fb = (self.rho * (ti * to / (np.pi * self.eta ** 2))[:, None]
                  * np.exp(-tau * (1 / mi_ + 1 / mo)))
        if self.base:
            out = np.where(reflect & ~flip, fr + fb, 0.0)
        else:
            out = np.where(reflect, fr, ft)
        return np.where(np.isfinite(out), out, 0.0)

    def specular(self, mu) -> np.ndarray:
        """The mirror reflection's reflectance F(μ) (n, channels)."""
        f = fresnel(np.atleast_1d(mu), self.eta)[:, None]
        return np.broadcast_to(f, (f.shape[0], self.tau.size)).copy()

    def unscattered(self, mu) -> np.ndarray:
        """The beam through the slab in −ωi, T² e^{−τ/μ'} (n, channels); 0 over a base."""
        mu = np.atleast_1d(np.asarray(mu, np.float64))
        mup = np.maximum(refracted(mu, self.eta), 1e-300)[:, None]
        t = (1 - fresnel(mu, self.eta))[:, None]
        return 0.0 * self.base + (not self.base) * t * t * np.exp(-self.tau[None, :] / mup)


class Exits:
    """The paths of :func:`walk` that left the slab: direction ``wo`` (m, 3), ``weight`` (m,)
    (flux per incident flux), the ``path`` each came from, scattering events ``order``
    (the base counts as one) and internal Fresnel ``reflections``; ``n`` paths were started."""

    def __init__(self, n: int):
        self.n, self.path = n, []
        self.wo, self.weight, self.order, self.reflections = [], [], [], []

    def add(self, path, wo, weight, order, reflections):
        for name, v in (("path", path), ("wo", wo), ("weight", weight), ("order", order),
                        ("reflections", reflections)):
            getattr(self, name).append(v)

    def done(self) -> "Exits":
        for name in ("path", "wo", "weight", "order", "reflections"):
            parts = getattr(self, name)
            setattr(self, name, np.concatenate(parts) if parts else np.zeros(0))
        return self

    def mean(self, select) -> tuple[float, float]:
        """(∫ f·|cosθo| dωo over the exits where ``select`` (a mask), its standard error)."""
        x = np.zeros(self.n)
        np.add.at(x, self.path.astype(int), np.where(select, self.weight, 0))
        return float(x.mean()), float(x.std() / np.sqrt(self.n))


def _exit(d, eta, mu_in) -> np.ndarray:
    """The outside direction of light leaving the slab along ``d`` at inside cosine μ."""
    mu_out = np.sqrt(np.maximum(1 - eta * eta * (1 - mu_in * mu_in), 0))
    return np.stack([d[:, 0] * eta, d[:, 1] * eta, np.sign(d[:, 2]) * mu_out], axis=1)


def walk(model: HK, wi, n: int, rng: np.random.Generator, channel: int = 0,
         max_events: int = 10_000) -> Exits:
    """
    A float64 random walk of ``n`` paths of one channel entering along −ωi (ωi above the
    surface): the entry's Fresnel transmission as a weight, then exponential free paths of σt,
    scattering by HG(g) with the weight times the albedo, at the top (and, without a base, the
    bottom) face Fresnel reflection or exit with the probabilities F and 1 − F, at a base
    Lambertian reflection with the weight times ρ. The exits' weights sample f·|cosθo|
    (flux, so the n² law of radiance is implicit): of every order, internal reflections
    included; the mirror reflection at entry is not among them (:meth:`HK.specular`).
    """
    eta, depth = model.eta, model.d
    sigma_t = model.sigma_s[channel % model.sigma_s.size] + \
        model.sigma_a[channel % model.sigma_a.size]
    albedo = model.albedo[channel % model.albedo.size]
    rho = model.rho[channel % model.rho.size]
    wi = np.asarray(wi, np.float64)
    mup = refracted(wi[2], eta)
    d = np.tile([-wi[0] / eta, -wi[1] / eta, -mup], (n, 1))
    z, index = np.zeros(n), np.arange(n)
    weight = np.full(n, 1 - float(fresnel(wi[2], eta)))
    order, bounces = np.zeros(n, int), np.zeros(n, int)
    out = Exits(n)
    for _ in range(max_events):
        if index.size == 0:
            break
        s = -np.log1p(-rng.random(index.size)) / sigma_t if sigma_t > 0 else np.inf
        z_new = z + s * d[:, 2]
        up, down = z_new >= 0, z_new <= -depth
        inside = ~(up | down)
        # scattering inside
        k = np.flatnonzero(inside)
        z[k], weight[k], order[k] = z_new[k], weight[k] * albedo, order[k] + 1
        d[k] = sample_hg(d[k], model.g, rng.random(k.size), rng.random(k.size))
        # the faces
        face = up | (down & (not model.base))
        z[up], z[down] = 0.0, -depth
        mu = np.abs(d[:, 2])
        leave = face & (rng.random(index.size) >= fresnel(mu, 1 / eta))
        out.add(index[leave], _exit(d[leave], eta, mu[leave]), weight[leave], order[leave],
                bounces[leave])
        turn = face & ~leave
        d[turn, 2], bounces[turn] = -d[turn, 2], bounces[turn] + 1
        if model.base:
            b = np.flatnonzero(down)
            u1, u2 = rng.random(b.size), rng.random(b.size)
            r, phi = np.sqrt(u1), 2 * np.pi * u2
            d[b] = np.stack([r * np.cos(phi), r * np.sin(phi), np.sqrt(1 - u1)], axis=1)
            weight[b], order[b] = weight[b] * rho, order[b] + 1
        keep = ~leave & (weight > 0)
        d, z, weight, order, bounces, index = (a[keep] for a in (d, z, weight, order,
                                                                  bounces, index))
    return out.done()

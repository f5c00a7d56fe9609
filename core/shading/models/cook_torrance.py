"""The Cook–Torrance lighting model (FvDFH 16.7; Cook and Torrance 1982): a registered model.

The surface is a field of V-shaped microfacets, each a perfect mirror. Per RGB channel λ:

    I_λ = I_aλ k_a O_dλ + Σ_lights f_att I_pλ [k_d O_dλ (N·L) + k_s F_λ D G / (N·V)]

which is FvDFH's ``I_r = I_i (N·L) dω_i (s R_s + d R_d)`` with the specular bidirectional
reflectivity ``R_s = F D G / (π (N·L)(N·V))`` in the Phong model's units (a light of
intensity ``I_p`` gives irradiance ``π I_p (N·L)``, so the diffuse term is Phong's own and the
BRDF is ``k_d O_d / π + k_s R_s``). With ``H = (L + V)/|L + V|`` and ``β`` the angle between
``N`` and ``H``:

- ``D = exp(−(tan β / m)²) / (4 m² cos⁴ β)``: Beckmann's distribution of facet slopes, rms
  slope ``m`` (the material's ``roughness``), as FvDFH writes it; ``π/4`` of the distribution
  normalised over the projected facet area, so ``R_s`` is the microfacet BRDF
  ``F D_n G / (4 (N·L)(N·V))`` of later papers;
- ``G = min(1, 2 (N·H)(N·V)/(V·H), 2 (N·H)(N·L)/(V·H))``: the facets' masking and shadowing;
- ``F_λ = F0_λ + (1 − F0_λ)(1 − V·H)^5``: Schlick's approximation to the Fresnel term (FvDFH
  evaluates the Fresnel equation for an index of refraction); ``F0`` (the material's ``f0``)
  is the reflectance at normal incidence and colours the highlight (``O_s`` is not used).

``halfway`` (the Phong model's choice of specular form) does not apply: the model is written
in ``H``. What keeps it finite: ``V``, ``L``, ``f_att``, the two-sided flip and the clamp are the
Phong model's (:func:`core.shading.illumination.toward_viewer`, ``toward_light``); no specular
term where ``N·L``, ``N·V``, ``V·H`` are not positive or ``N·H < 1e-8`` (there ``D`` is below
``exp(−10^16)``: zero), so the ``1/(N·V)`` and ``1/cos⁴ β`` never divide by zero.

For the path tracer the glossy lobe is ``k_s F D G / (π (N·L)(N·V))`` and its directions are
drawn from Beckmann's distribution of ``H`` (``tan² β = −m² ln(1 − u1)``, ``φ = 2π u2``;
Walter et al. 2007), ``ω_i`` the mirror of ``ω_o`` about ``H``, with pdf
``D_n (N·H) / (4 (ω_o·H))``, ``D_n = 4 D / π``.
"""

from __future__ import annotations

import math

from core.jit import njit
from core.shading.illumination import (KA, KD, KS, OD, PARAMETERS, toward_light, toward_viewer,
                                       two_sided_normal)
from core.vectors import around, unit3

ROUGHNESS, F0 = PARAMETERS, PARAMETERS + 1        # columns of the surface row
FLAT = 1e-8                  # N·H below this: D is exp(−1e16 / m²), zero


@njit(cache=True, inline="always")
def microfacet(nx, ny, nz, vx, vy, vz, lx, ly, lz, m):
    """``(D, G, V·H, N·H)`` for unit N, V, L and rms slope ``m``; D = 0 where the model gives
    no specular term (see the module)."""
    hx, hy, hz, h_len = unit3(lx + vx, ly + vy, lz + vz)
    nh = nx * hx + ny * hy + nz * hz
    vh = vx * hx + vy * hy + vz * hz
    nv = nx * vx + ny * vy + nz * vz
    nl = nx * lx + ny * ly + nz * lz
    if not (h_len > 0.0 and nh > FLAT and vh > 0.0 and nv > 0.0 and nl > 0.0):
        return 0.0, 0.0, 0.0, 0.0
    cos2 = nh * nh
    tan2 = (1.0 - cos2) / cos2
    m2 = m * m
    d = math.exp(-tan2 / m2) / (4.0 * m2 * cos2 * cos2)
    g = min(1.0, 2.0 * nh * nv / vh, 2.0 * nh * nl / vh)
    return d, g, vh, nh


@njit(cache=True, inline="always")
def schlick(f0, vh):
    """``F0 + (1 − F0)(1 − V·H)^5``."""
    c = 1.0 - vh
    return f0 + (1.0 - f0) * (c * c * c * c * c)


@njit(cache=True, inline="always")
def point(px, py, pz, nx, ny, nz, s, surfaces, lights, ambient, eye, halfway):
    """The model at world point P with unit (or zero) normal N for surface row ``s``:
    ``(r, g, b)`` clamped to [0, 1] (the signature of ``phong_point``)."""
    ka, kd, ks, m = surfaces[s, KA], surfaces[s, KD], surfaces[s, KS], surfaces[s, ROUGHNESS]
    vx, vy, vz = toward_viewer(eye, px, py, pz, nx, ny, nz)
    nx, ny, nz = two_sided_normal(surfaces, s, nx, ny, nz, vx, vy, vz)
    nv = nx * vx + ny * vy + nz * vz
    r = ambient[0] * ka * surfaces[s, OD]
    g = ambient[1] * ka * surfaces[s, OD + 1]
    b = ambient[2] * ka * surfaces[s, OD + 2]
    for k in range(lights.shape[0]):
        lx, ly, lz, f_att = toward_light(lights, k, px, py, pz)
        n_dot_l = nx * lx + ny * ly + nz * lz
        if not n_dot_l > 0.0:           # behind the surface, or the light on the point
            continue
        d, geometry, vh, _ = microfacet(nx, ny, nz, vx, vy, vz, lx, ly, lz, m)
        spec = ks * d * geometry / nv if d > 0.0 else 0.0
        r += f_att * lights[k, 4] * (kd * surfaces[s, OD] * n_dot_l
                                     + spec * schlick(surfaces[s, F0], vh))
        g += f_att * lights[k, 5] * (kd * surfaces[s, OD + 1] * n_dot_l
                                     + spec * schlick(surfaces[s, F0 + 1], vh))
        b += f_att * lights[k, 6] * (kd * surfaces[s, OD + 2] * n_dot_l
                                     + spec * schlick(surfaces[s, F0 + 2], vh))
    return min(max(r, 0.0), 1.0), min(max(g, 0.0), 1.0), min(max(b, 0.0), 1.0)


@njit(cache=True, inline="always")
def glossy(m, at, nx, ny, nz, wox, woy, woz, wix, wiy, wiz, ps):
    """The path tracer's lobe: ``k_s F D G / (π (N·L)(N·V))`` (RGB) at ``ω_i`` and ``ps`` x
    the pdf of :func:`sample_glossy` choosing it."""
    d, geometry, vh, nh = microfacet(nx, ny, nz, wox, woy, woz, wix, wiy, wiz, m[at + ROUGHNESS])
    if not d > 0.0:
        return 0.0, 0.0, 0.0, 0.0
    nl = nx * wix + ny * wiy + nz * wiz
    nv = nx * wox + ny * woy + nz * woz
    s = m[at + KS] * d * geometry / (math.pi * nl * nv)
    return (s * schlick(m[at + F0], vh), s * schlick(m[at + F0 + 1], vh),
            s * schlick(m[at + F0 + 2], vh), ps * d * nh / (math.pi * vh))


@njit(cache=True, inline="always")
def sample_glossy(m, at, nx, ny, nz, wox, woy, woz, u1, u2):
    """``ω_i``: ``ω_o`` mirrored about a facet normal ``H`` drawn from Beckmann's distribution."""
    rough = m[at + ROUGHNESS]
    tan2 = -rough * rough * math.log(1.0 - u1)
    cos_b = 1.0 / math.sqrt(1.0 + tan2)
    sin_b = math.sqrt(max(0.0, 1.0 - cos_b * cos_b))
    phi = 2.0 * math.pi * u2
    hx, hy, hz = around(nx, ny, nz, sin_b * math.cos(phi), sin_b * math.sin(phi), cos_b)
    c = 2.0 * (wox * hx + woy * hy + woz * hz)
    return c * hx - wox, c * hy - woy, c * hz - woz


def terms(p, n, s, surfaces, lights, ambient, eye, halfway, shadow=None) -> dict:
    """The model term by term for the pixel inspector (the compiled steps, called one by one):
    per light ``L``, ``N·L``, ``f_att``, ``H``'s cosines, ``D``, ``G``, ``F`` and the two terms;
    ``sum`` unclamped, ``clamped`` the model's value. ``shadow``: per light, an RGB factor on
    ``I_p`` (the ray tracer's shadow rays; 1 for the z-buffer)."""
    px, py, pz = (float(c) for c in p)
    nx, ny, nz = (float(c) for c in n)
    ka, kd, ks, m = (float(surfaces[s, c]) for c in (KA, KD, KS, ROUGHNESS))
    od = [float(surfaces[s, OD + c]) for c in range(3)]
    f0 = [float(surfaces[s, F0 + c]) for c in range(3)]
    vx, vy, vz = toward_viewer(eye, px, py, pz, nx, ny, nz)
    fx, fy, fz = two_sided_normal(surfaces, s, nx, ny, nz, vx, vy, vz)
    flipped = (fx, fy, fz) != (nx, ny, nz)
    nx, ny, nz = fx, fy, fz
    nv = nx * vx + ny * vy + nz * vz
    amb = [float(ambient[c]) * ka * od[c] for c in range(3)]
    total, per_light = list(amb), []
    for k in range(lights.shape[0]):
        row = {"light": k + 1, "kind": "point" if lights[k, 0] == 0.0 else "directional"}
        per_light.append(row)
        lx, ly, lz, f_att = toward_light(lights, k, px, py, pz)
        n_dot_l = nx * lx + ny * ly + nz * lz
        row.update({"L": [lx, ly, lz], "N.L": n_dot_l, "attenuation": float(f_att)})
        if not n_dot_l > 0.0:
            row["note"] = "the light is behind the surface (or on the point): no diffuse, no specular"
            continue
        d, geometry, vh, nh = microfacet(nx, ny, nz, vx, vy, vz, lx, ly, lz, m)
        spec = ks * d * geometry / nv if d > 0.0 else 0.0
        fresnel = [schlick(f0[c], vh) for c in range(3)]
        factor = [1.0, 1.0, 1.0] if shadow is None else [float(c) for c in shadow[k]]
        ip = [float(lights[k, 4 + c]) * factor[c] for c in range(3)]
        row.update({"shadow": factor, "N.H": nh, "V.H": vh, "N.V": nv, "D": d, "G": geometry,
                    "F": fresnel,
                    "diffuse": [f_att * ip[c] * (kd * od[c] * n_dot_l) for c in range(3)],
                    "specular": [f_att * ip[c] * (spec * fresnel[c]) for c in range(3)]})
        for c in range(3):          # point's own expression: the same bits
            total[c] += f_att * ip[c] * (kd * od[c] * n_dot_l + spec * fresnel[c])
        row["sum"] = [row["diffuse"][c] + row["specular"][c] for c in range(3)]
    return {"P": [px, py, pz], "N": [nx, ny, nz], "V": [vx, vy, vz], "two-sided flip": flipped,
            "k_a": ka, "k_d": kd, "k_s": ks, "roughness": m, "f0": f0, "O_d": od,
            "ambient": amb, "lights": per_light, "sum": total,
            "clamped": [min(max(c, 0.0), 1.0) for c in total]}

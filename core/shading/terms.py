"""The Phong model's terms one by one, for the pixel inspector.

:func:`phong_terms` is :func:`core.shading.illumination.phong_point` written out in Python,
step for step and in the same order of operations, keeping what the compiled model only
sums: the ambient term and, per light, ``L``, ``N·L``, ``f_att``, the shadow factor, the
diffuse and the specular term. Its ``sum`` is the model's value before the clamp, to the last
bit (the same IEEE operations in the same order); the inspector's tests hold it against the
compiled kernels' pixels.
"""

from __future__ import annotations

from core.shading.illumination import (EXPONENT, EYE_POINT, KA, KD, KS, LIGHT_CAP, OD, OS,
                                       POINT_LIGHT, TWO_SIDED, attenuation, specular_power,
                                       unit3)


def phong_terms(p, n, s, surfaces, lights, ambient, eye, halfway, shadow=None) -> dict:
    """The model at world point ``p`` with unit normal ``n`` for surface row ``s``, term by term.

    ``shadow`` (per light, an RGB factor on ``I_p``; the ray tracer's shadow rays) defaults to
    1: the z-buffer casts no shadows. Returns a JSON-able dict whose ``sum`` (RGB) is the
    unclamped value and ``clamped`` the model's result.
    """
    px, py, pz = (float(c) for c in p)
    ka, kd, ks, e = (float(surfaces[s, c]) for c in (KA, KD, KS, EXPONENT))
    od = [float(surfaces[s, OD + c]) for c in range(3)]
    os_ = [float(surfaces[s, OS + c]) for c in range(3)]
    (vx, vy, vz), (nx, ny, nz), flipped = _view_and_normal((px, py, pz), n, s, surfaces, eye)
    amb = [float(ambient[c]) * ka * od[c] for c in range(3)]
    total = list(amb)
    per_light = [_light_terms(k, lights, (px, py, pz), (nx, ny, nz), (vx, vy, vz),
                              (kd, ks, e, od, os_), halfway, shadow, total)
                 for k in range(lights.shape[0])]
    return {"P": [px, py, pz], "N": [nx, ny, nz], "V": [vx, vy, vz],
            "two-sided flip": flipped, "k_a": ka, "k_d": kd, "k_s": ks, "n": e, "O_d": od,
            "O_s": os_, "ambient": amb, "lights": per_light, "sum": total,
            "clamped": [min(max(c, 0.0), 1.0) for c in total]}


def _view_and_normal(p, n, s, surfaces, eye):
    """``V`` towards the eye (a point, or a direction), and ``N`` turned towards it when the
    surface is two-sided and faces away: (V, N, whether N was flipped)."""
    px, py, pz = p
    nx, ny, nz = (float(c) for c in n)
    if eye[0] == EYE_POINT:
        vx, vy, vz, dist = unit3(eye[1] - px, eye[2] - py, eye[3] - pz)
        if dist == 0.0:
            vx, vy, vz = nx, ny, nz
    else:
        vx, vy, vz = float(eye[1]), float(eye[2]), float(eye[3])
    flipped = bool(surfaces[s, TWO_SIDED] != 0.0 and nx * vx + ny * vy + nz * vz < 0.0)
    if flipped:
        nx, ny, nz = -nx, -ny, -nz
    return (vx, vy, vz), (nx, ny, nz), flipped


def _light_terms(k, lights, p, n, v, material, halfway, shadow, total) -> dict:
    """Light ``k``'s row: ``L``, ``N·L``, ``f_att``, the shadow factor, the diffuse and
    specular terms; adds its share to ``total`` as phong_point does (the same bits)."""
    px, py, pz = p
    nx, ny, nz = n
    vx, vy, vz = v
    kd, ks, e, od, os_ = material
    row = {"light": k + 1, "kind": "point" if lights[k, 0] == POINT_LIGHT else "directional"}
    if lights[k, 0] == POINT_LIGHT:
        lx, ly, lz, d = unit3(lights[k, 1] - px, lights[k, 2] - py, lights[k, 3] - pz)
        row["distance"] = d
        if d == 0.0:
            row["note"] = "the light is on the point: ambient only"
            return row
        den = lights[k, 7] + lights[k, 8] * d + lights[k, 9] * d * d
        f_att = float(attenuation(den, lights[k, LIGHT_CAP]))
    else:
        lx, ly, lz = lights[k, 1], lights[k, 2], lights[k, 3]
        f_att = 1.0
    n_dot_l = nx * lx + ny * ly + nz * lz
    row.update({"L": [lx, ly, lz], "N.L": n_dot_l, "attenuation": float(f_att)})
    if not n_dot_l > 0.0:
        row["note"] = "the light is behind the surface: no diffuse, no specular"
        return row
    if halfway:
        hx, hy, hz, _ = unit3(lx + vx, ly + vy, lz + vz)
        base = nx * hx + ny * hy + nz * hz
    else:
        two_n_dot_l = 2 * n_dot_l
        rx, ry, rz = two_n_dot_l * nx - lx, two_n_dot_l * ny - ly, two_n_dot_l * nz - lz
        base = rx * vx + ry * vy + rz * vz
    spec = specular_power(base, e)
    factor = [1.0, 1.0, 1.0] if shadow is None else [float(c) for c in shadow[k]]
    ip = [float(lights[k, 4 + c]) * factor[c] for c in range(3)]
    row.update({"shadow": factor, "specular base": base, "specular power": spec,
                "diffuse": [f_att * ip[c] * (kd * od[c] * n_dot_l) for c in range(3)],
                "specular": [f_att * ip[c] * (ks * os_[c] * spec) for c in range(3)]})
    for c in range(3):         # phong_point's own expression: the same bits
        total[c] += f_att * ip[c] * (kd * od[c] * n_dot_l + ks * os_[c] * spec)
    row["sum"] = [row["diffuse"][c] + row["specular"][c] for c in range(3)]
    return row

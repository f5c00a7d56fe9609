"""A pixel record as short lines of text: what ``inspect`` prints and the window's panel shows.

The lines are plain ASCII-friendly text (the window's font has few glyphs), the most telling
first: the pixel and its colour, what covers it, the weights and depth, then the sum
(Phong's terms per light, the texture, the ray tree). Other keys are left to ``--json``.
"""

from __future__ import annotations


def _v(values, digits: int = 4) -> str:
    return "(" + ", ".join(f"{float(v):.{digits}g}" for v in values) + ")"


def _rgb(values) -> str:
    return "(" + ", ".join(f"{float(v):.4f}" for v in values) + ")"


def describe(record: dict) -> list[str]:
    """The record's lines (the first names the pixel, the renderer and the colour). A record
    of a shape this module does not know (another renderer's) is listed key by key."""
    x, y = record["pixel"]
    r, g, b = record["color"]
    lines = [f"pixel ({x}, {y})  {record['renderer']}  colour ({r}, {g}, {b})"]
    try:
        lines += _body({k: v for k, v in record.items() if k != "scan line"})
    except (KeyError, TypeError, IndexError, ValueError):
        lines += _generic(record)
    if isinstance(record.get("scan line"), dict):
        lines += _scan_line(record["scan line"])
    return lines


def _scan_line(line: dict, limit: int = 24) -> list[str]:
    """Watkins' active edge table on the pixel's scan line, and the spans it cut the line into."""
    aet, spans = line.get("aet", []), line.get("spans", [])
    out = [f"scan line {line['image row']} (device row {line['device row']}): AET of "
           f"{len(aet)} edges, sorted in x"]
    for e in aet[:limit]:
        out.append(f"  x {e['x']:9.4f}  {e['edge']:5s} edge of triangle {e['triangle']}"
                   f" ({'first' if e['edge'] == 'left' else 'last'} pixel {e['pixel']})")
    out.append(f"  spans: {len(spans)}")
    for s in spans[:limit]:
        out.append(f"  pixels {s['pixels'][0]}-{s['pixels'][1]}: triangle "
                   f"{s['visible triangle']}, {s['polygons in']} in, {s['decided']}")
    return out


def _generic(record: dict, limit: int = 40) -> list[str]:
    out = []
    for key, value in record.items():
        if key in ("renderer", "pixel", "color"):
            continue
        text = repr(value)
        out.append(f"{key}: {text if len(text) <= 160 else text[:157] + '...'}")
    return out[:limit]


def _body(record: dict) -> list[str]:
    lines = []
    if "samples" in record and record.get("samples per pixel"):
        lines.append(f"{record['samples per pixel']} samples, averaged; the first:")
        return lines + _sample(record["samples"][0])
    if "ray samples" in record:
        return lines + _ray_samples(record)
    if "ray tree" in record or "samples" in record:
        return lines + _ray_tree(record)
    if "rays" in record and "radiance" in record:
        return lines + _two_pass(record)
    if record.get("layer") is None and "weights" not in record:
        return _generic(record)
    return lines + _sample(record)


def _two_pass(record: dict, limit: int = 24) -> list[str]:
    """The two-pass renderer's ray tree: each ray, what it hit, the diffuse term pass 1 gave
    there and the specular terms; the radiance the pixel sums."""
    out = [f"radiance {_rgb(record['radiance'])} (tone {record['tone']}): the sum of each "
           "ray's weight x (diffuse from pass 1 + highlight)"]
    for ray in record["rays"][:limit]:
        head = f"{'  ' * ray['depth']}{ray['ray']}, weight {ray['weight']:.4g}: "
        if ray["hit"] is None:
            out.append(head + "leaves the scene (the background)")
            continue
        out.append(head + f"{ray['hit']} (element {ray['element']}, t {ray['t']:.4g}): "
                   f"diffuse {_rgb(ray['diffuse (pass 1)'])}, highlight "
                   f"{_rgb(ray['highlight'])}, k_r {ray['k_r']:g}, k_t {ray['k_t']:g}")
    if len(record["rays"]) > limit:
        out.append(f"  ... {len(record['rays']) - limit} more rays (--json lists them all)")
    return out


def _sample(record: dict) -> list[str]:
    layer = record.get("layer")
    if layer == "background":
        return ["background: no triangle covers the pixel centre"]
    if layer == "line":
        return ["line: drawn by the line pass over the triangles"]
    if layer != "triangle":
        return [f"{k}: {v}" for k, v in record.items() if k not in ("renderer", "pixel", "color")][:12]
    w, d = record["weights"], record["depth"]
    lines = [f"mesh {record['mesh']} ({record.get('mesh name')}), triangle {record['triangle']}"
             + (" (clipped)" if record.get("made by the clipper") else ""),
             f"weights {w['kind']} {_v(w['used'])}"]
    if "screen-linear" in w:
        lines.append(f"  screen-linear {_v(w['screen-linear'])}")
        lines.append(f"  perspective-correct {_v(w['perspective-correct'])}")
    lines.append(f"depth NPC {d['npc']:.6f}, world {_v(d['world point'], 6)}")
    if "distance from the eye" in d:
        lines.append(f"  {d['distance from the eye']:.6g} from the eye")
    if "normal" in record:
        lines.append(f"normal {_v(record['normal'])}")
    if "texture" in record:
        t = record["texture"]
        lines.append(f"uv {_v(record['uv'])}, {record.get('texture filter')}, MIP level "
                     f"{float(t['mip level']):.3f}, {len(t['texels'])} texels read")
        for texel in t["texels"][:8]:
            lines.append(f"  level {texel['level']} texel ({texel['i']}, {texel['j']}) "
                         f"x {texel['weight']:.4f} = {_rgb(texel['rgba'][:3])}")
        lines.append(f"  O_d {_rgb(t['O_d'])}")
    if "phong" in record:
        lines += _phong(record["phong"], record.get("evaluated at"))
    if "vertices" in record:
        for k, vertex in enumerate(record["vertices"]):
            lines.append(f"vertex {k}: colour {_rgb(vertex['colour'])}")
            if "phong" in vertex:
                lines += ["  " + line for line in _phong(vertex["phong"], None)[1:]]
        lines.append(f"interpolated {_rgb(record['interpolated colour'])}")
    if "environment" in record:
        e = record["environment"]
        lines.append(f"environment x {e['reflectivity']:.3f}: {_rgb(e['colour'])}")
    if "sum" in record:
        lines.append(f"sum {_rgb(record['sum'])}")
    return lines


def _phong(terms: dict, where) -> list[str]:
    lines = [f"{terms.get('model label', 'Phong')} at {where or 'the pixel'}: N {_v(terms['N'])}"
             + (" (turned to the viewer)" if terms.get("two-sided flip") else "")]
    lines.append(f"ambient {_rgb(terms['ambient'])}")
    for light in terms["lights"]:
        if "diffuse" in light:
            shadow = light.get("shadow", [1, 1, 1])
            lines.append(f"light {light['light']}: N.L {light['N.L']:.4f}, att "
                         f"{light['attenuation']:.4f}, shadow {_v(shadow, 3)}")
            lines.append(f"  diffuse {_rgb(light['diffuse'])} specular {_rgb(light['specular'])}")
        else:
            lines.append(f"light {light['light']}: {light.get('note', 'no contribution')}")
    lines.append(f"sum {_rgb(terms['sum'])} -> {_rgb(terms['clamped'])}")
    return lines


def _ray_tree(record: dict) -> list[str]:
    nodes = record.get("ray tree")
    if nodes is None:
        nodes = record["samples"][0]["nodes"]
        lines = [f"{len(record['samples'])} samples, averaged; the first's ray tree:"]
    else:
        lines = [f"ray tree ({len(nodes)} rays, depth {record.get('ray-tree depth')}):"]
    for node in nodes[:24]:
        hit = node.get("hit")
        where = "background" if hit is None else f"{hit['kind']} {hit['index']} t {hit['t']:.4g}"
        lines.append(f"{'  ' * (node['depth'] - 1)}{node['kind']} x {node['weight']:.3f}: "
                     f"{where}, local {_rgb(node['local colour'])}, adds "
                     f"{_rgb(node['contribution'])}")
    if "raw" in record:
        lines.append(f"sum {_rgb(record['raw'])}")
    return lines


def _ray_samples(record: dict) -> list[str]:
    """The ray caster: each sample's hit and Phong sum (the first eight)."""
    lines = [f"{record['samples per pixel']} samples, coverage {record['coverage']:.3f}"]
    for sample in record["ray samples"][:8]:
        hit = sample["hit"]
        if hit is None:
            lines.append("  background")
        else:
            lines.append(f"  primitive {hit['primitive']} t {hit['t']:.5g}: "
                         f"{_rgb(sample['phong']['clamped'])}")
    lines.append(f"mean {_rgb(record['raw'])}")
    return lines

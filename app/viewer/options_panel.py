"""The panel's renderer-options section: one control per option of the current renderer.

The controls come from :func:`app.session.options.controls` (the renderer's registered options
class); every change goes through ``state.choices.set_option``, which keeps the last good
value and says why when the class refuses one. Numbers are taken when Enter is pressed (or a
step button clicked), so a ray-traced picture is not re-drawn at every keystroke.
"""

from __future__ import annotations

import logging

log = logging.getLogger("fvd")


def draw(imgui, state, displayable) -> None:
    """The samples per pixel, then the section under a header named for the renderer (none
    for a renderer without options)."""
    from app.session.options import controls
    from core.registry import get_renderer
    _samples(imgui, state)
    found = controls(state.choices.renderer_options())
    if not found:
        _message(imgui, state, displayable)
        return
    label = get_renderer(state.renderer_name or "zbuffer").label
    if not imgui.collapsing_header(displayable(f"{label}: options") + "###renderer-options"):
        return
    imgui.push_item_width(imgui.get_content_region_avail().x * 0.5)   # half for the names
    for control in found:
        changed, value = _control(imgui, control)
        if control.help and imgui.is_item_hovered():
            imgui.set_tooltip(control.help)
        if changed:
            ok = state.choices.set_option(control.name, value)
            log.info("action: panel %s -> %s", control.name,
                     repr(value) if ok else state.option_message)
    imgui.pop_item_width()
    _message(imgui, state, displayable)
    imgui.separator()


def _message(imgui, state, displayable) -> None:
    if state.option_message:
        imgui.push_text_wrap_pos(0.0)
        imgui.text_colored((1.0, 0.45, 0.4, 1.0), displayable(state.option_message))
        imgui.pop_text_wrap_pos()


def _samples(imgui, state) -> None:
    """Samples per pixel (taken on Enter): the path tracer's passes add up to it at rest."""
    imgui.push_item_width(imgui.get_content_region_avail().x * 0.5)
    shown = state.choices.samples_wanted or 1
    changed, value = imgui.input_int("samples per pixel##film-samples", int(shown), 1, 16,
                                     imgui.InputTextFlags_.enter_returns_true)
    imgui.pop_item_width()
    if imgui.is_item_hovered():
        imgui.set_tooltip("samples per pixel of the next frames; the path tracer adds one "
                          "pass at a time while the camera rests")
    if changed and value != shown:
        ok = state.choices.set_samples(int(value))
        log.info("action: panel samples per pixel -> %s", value if ok else state.option_message)


def _control(imgui, control) -> tuple[bool, object]:
    """Draw one control; (whether it was changed, its value)."""
    enter = imgui.InputTextFlags_.enter_returns_true
    name = f"{control.label}##option-{control.name}"
    if control.kind == "bool":
        return imgui.checkbox(name, bool(control.value))
    if control.kind == "choice":
        choices = list(control.choices)
        current = choices.index(control.value) if control.value in choices else 0
        changed, k = imgui.combo(name, current, choices)
        return changed, choices[k]
    if control.kind == "int":
        return imgui.input_int(name, int(control.value), 1, 10, enter)
    if control.kind == "float":
        return imgui.input_float(name, float(control.value), 0.0, 0.0, "%.4g", enter)
    first, second = (float(v) for v in control.value)
    changed, pair = imgui.input_float2(name, imgui.ImVec2(first, second), "%.4g", enter)
    return changed, (float(pair.x), float(pair.y))

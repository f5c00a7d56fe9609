"""What the tests need from the machine, and one rule for when it is missing.

Without ``CI`` in the environment a missing tool skips the test with its reason (a developer's
machine may lack Xvfb). With ``CI`` set a missing tool is a failure: ``.ci/run`` installs every
tool the tests use, so a skip there would make a green run mean less than it says.
"""

from __future__ import annotations

import importlib
import os
import shutil

import pytest


def unavailable(reason: str):
    """Skip with ``reason``, or fail with it when ``CI`` is set."""
    if os.environ.get("CI"):
        pytest.fail(f"{reason} (CI is set: .ci/run must install every tool the tests use)",
                    pytrace=False)
    pytest.skip(reason, allow_module_level=True)


def need_module(name: str, why: str):
    """Import ``name`` or give up the test as :func:`unavailable`."""
    try:
        return importlib.import_module(name)
    except ImportError as error:
        unavailable(f"{why}: {error}")


def need_programs(*names: str, install: str) -> None:
    missing = [name for name in names if shutil.which(name) is None]
    if missing:
        unavailable(f"{' and '.join(missing)} not installed ({install})")


def llvmpipe_context():
    """A standalone EGL context on Mesa's llvmpipe: the outside oracle nobody here wrote.

    Only the context's creation may give up the test; everything after it (shader
    compilation, drawing) is the test's own and fails loudly. A context on another renderer
    is refused: the oracle's tolerances were measured on llvmpipe.
    """
    moderngl = need_module("moderngl", "the OpenGL oracle needs moderngl")
    try:
        ctx = moderngl.create_standalone_context(backend="egl")
    except Exception as error:            # no EGL or no Mesa on this machine
        unavailable(f"no headless EGL OpenGL context (apt-get install libegl-mesa0 "
                    f"libgl1-mesa-dri): {error}")
    renderer = ctx.info["GL_RENDERER"]
    assert "llvmpipe" in renderer, f"the GL oracle must be Mesa's llvmpipe, not {renderer!r}"
    return ctx

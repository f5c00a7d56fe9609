"""Shared test set-up: seeded randomness, numpy warnings as errors, golden-image helpers, and
the paths every test folder uses (``from tests.conftest import ROOT``: tests/core/<package>/
and tests/app/<package>/ mirror the source tree, so no test counts its own parents)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

TESTS = Path(__file__).resolve().parent
ROOT = TESTS.parent
DATA = TESTS / "data"
GOLDEN = TESTS / "golden"
FAILURES = TESTS / "_failures"
SHARED = ROOT.parent / "shared"
BUNNY = SHARED / "data" / "stanford-bunny" / "bun_zipper.ply"
# Golden images: a pixel may differ by one level (1/255) per channel, on at most 0.1 % of them.
GOLDEN_LEVELS = 1
GOLDEN_PIXEL_SHARE = 0.001


def pytest_collection_modifyitems(session, config, items):
    """The warm-up's completeness test goes first: no other test may have compiled a kernel
    into the cache before it looks (tests/app/distribution/test_warmup_complete.py)."""
    first = [item for item in items if item.fspath.basename == "test_warmup_complete.py"]
    items[:] = first + [item for item in items if item not in first]


def pytest_addoption(parser):
    parser.addoption("--update-golden", action="store_true",
                     help="rewrite the golden images from the current renderer (look at them!)")


@pytest.fixture(autouse=True, scope="session")
def _own_config_dir(tmp_path_factory):
    """The viewer keeps File > Recent in the user's config directory: tests and the windows
    they start (which inherit the environment) keep theirs in a temporary one instead."""
    import os
    before = os.environ.get("FVD_CONFIG_DIR")
    os.environ["FVD_CONFIG_DIR"] = str(tmp_path_factory.mktemp("config"))
    yield
    if before is None:
        os.environ.pop("FVD_CONFIG_DIR", None)
    else:
        os.environ["FVD_CONFIG_DIR"] = before


@pytest.fixture(autouse=True)
def _numpy_strict():
    """Seed numpy and make every silent NaN, overflow or division by zero fail the test."""
    np.random.seed(12345)
    old = np.seterr(all="raise", under="ignore")   # underflow to 0 is harmless
    yield
    np.seterr(**old)


@pytest.fixture
def golden(request):
    """``golden(name, image)``: compare an (H, W, 3) uint8 image with tests/golden/NAME.png.

    The comparison has a stated tolerance (README, "Tests"): at most ``GOLDEN_PIXEL_SHARE`` of
    the pixels may differ, each channel by at most ``GOLDEN_LEVELS`` (1/255). The pipeline is
    deterministic, but its twins (serial and parallel kernels, float32 and float64 shading,
    pow and repeated squaring) are no longer held to bit-identity: a rounding that tips a
    value across a half level changes a byte by one. On a failure the actual image and a diff
    image (white: beyond tolerance, grey: within it) are written to tests/_failures/ and the
    test fails with the counts.
    """
    from PIL import Image
    update = request.config.getoption("--update-golden")

    def check(name: str, image: np.ndarray) -> None:
        path = GOLDEN / f"{name}.png"
        if update:
            GOLDEN.mkdir(exist_ok=True)
            Image.fromarray(image).save(path)
            return
        assert path.exists(), f"no golden image {path}; run pytest --update-golden and look at it"
        expected = np.asarray(Image.open(path).convert("RGB"))
        if expected.shape == image.shape:
            error = np.abs(expected.astype(np.int16) - image.astype(np.int16)).max(axis=2)
            differ = int(np.count_nonzero(error))
            beyond = int(np.count_nonzero(error > GOLDEN_LEVELS))
            if beyond == 0 and differ <= GOLDEN_PIXEL_SHARE * error.size:
                return
        FAILURES.mkdir(exist_ok=True)
        Image.fromarray(image).save(FAILURES / f"{name}.actual.png")
        if expected.shape == image.shape:
            diff = np.where(error > GOLDEN_LEVELS, 255, np.where(error > 0, 96, 0)).astype(np.uint8)
            Image.fromarray(diff).save(FAILURES / f"{name}.diff.png")
            pytest.fail(f"{name}: {differ} pixels differ from {path} ({beyond} by more than "
                        f"{GOLDEN_LEVELS}/255; allowed: none beyond, at most "
                        f"{GOLDEN_PIXEL_SHARE:.1%} of {error.size} within) (see {FAILURES})")
        pytest.fail(f"{name}: shape {image.shape} != golden {expected.shape}")

    return check


@pytest.fixture
def bunny_path():
    if not BUNNY.exists():
        pytest.skip(f"the Stanford bunny is not at {BUNNY} (../shared is absent)")
    return BUNNY

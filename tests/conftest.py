"""Shared test set-up: seeded randomness, numpy warnings as errors, golden-image helpers."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parent.parent
GOLDEN = Path(__file__).resolve().parent / "golden"
FAILURES = Path(__file__).resolve().parent / "_failures"
SHARED = ROOT.parent / "shared"
BUNNY = SHARED / "data" / "stanford-bunny" / "bun_zipper.ply"


def pytest_addoption(parser):
    parser.addoption("--update-golden", action="store_true",
                     help="rewrite the golden images from the current renderer (look at them!)")


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

    The comparison is exact (the pipeline is deterministic). On a mismatch the actual image and
    a diff image are written to tests/_failures/ and the test fails with the count of pixels.
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
        if expected.shape == image.shape and np.array_equal(expected, image):
            return
        FAILURES.mkdir(exist_ok=True)
        Image.fromarray(image).save(FAILURES / f"{name}.actual.png")
        if expected.shape == image.shape:
            diff = (np.any(expected != image, axis=2) * 255).astype(np.uint8)
            Image.fromarray(diff).save(FAILURES / f"{name}.diff.png")
            count = int(np.count_nonzero(diff))
            pytest.fail(f"{name}: {count} pixels differ from {path} (see {FAILURES})")
        pytest.fail(f"{name}: shape {image.shape} != golden {expected.shape}")

    return check


@pytest.fixture
def bunny_path():
    if not BUNNY.exists():
        pytest.skip(f"the Stanford bunny is not at {BUNNY} (../shared is absent)")
    return BUNNY

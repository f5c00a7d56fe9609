"""Fuzzing the readers: mutated valid files and random bytes give a ReaderError or a scene
that renders (the invariant of ``tests/fuzz_targets.py``).

Nothing else may escape (no IndexError, no FloatingPointError, no MemoryError), every
ReaderError has a one-line message, every scene a reader returns is drawn in both projections
through ``core.render.render`` without an exception, and no input makes a reader allocate
much: the counts written in a file are never trusted. Example counts stay modest so that the
suite stays fast; ``tests/fuzz_long.py`` runs the same targets 100k times each.
"""

from __future__ import annotations

import re
import struct
import tracemalloc

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import trimesh.exchange.load  # noqa: F401  (imported before tracing: importing allocates)

from core.scene.formats import ReaderError, read_mesh, read_scene_file, read_tri
from core.paths import SCENES_DIR
from tests.conftest import TESTS
from fuzz_targets import (NASTY, OBJ, OFF, PLY, STL_ASCII, STL_BINARY, SYSTEMS, TARGETS, TOML,
                          TRI, check, mutate_any, renders, small_budgets)

# Peak memory a reader may take for these small inputs (the inputs are a few KB).
MEMORY_LIMIT = 32_000_000

FUZZ = settings(max_examples=60, deadline=None, derandomize=True,
                suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])


@st.composite
def mutated(draw, base: bytes) -> bytes:
    """``base`` with a few byte-level and token-level edits."""
    data = bytearray(base)
    for _ in range(draw(st.integers(1, 4))):
        kind = draw(st.sampled_from(["byte", "insert", "delete", "truncate", "token", "repeat"]))
        at = draw(st.integers(0, max(len(data) - 1, 0)))
        if kind == "byte" and data:
            data[at] = draw(st.integers(0, 255))
        elif kind == "insert":
            data[at:at] = draw(st.binary(max_size=8))
        elif kind == "delete":
            del data[at:at + draw(st.integers(1, 24))]
        elif kind == "truncate":
            del data[at:]
        elif kind == "repeat":
            data[at:at] = data[at:at + draw(st.integers(1, 60))]
        else:
            spans = [m.span() for m in re.finditer(rb"[^\s,=\[\]{}]+", bytes(data))]
            if spans:
                a, b = spans[draw(st.integers(0, len(spans) - 1))]
                data[a:b] = draw(st.sampled_from(NASTY))
    return bytes(data)


def only_reader_errors(read, data: bytes) -> None:
    """``read(data)`` returns something or raises ReaderError with a message; memory stays low."""
    tracemalloc.start()
    result = None
    try:
        try:
            with small_budgets():
                result = read(data)
        except ReaderError as error:
            assert str(error).strip() and error.reason.strip()
            assert "\n" not in str(error) and "\x1b" not in str(error)
        else:
            assert result is not None
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert peak < MEMORY_LIMIT, f"{peak} bytes for a {len(data)}-byte input"
    if result is not None:
        with small_budgets():      # a mutated emitter may ask for a day of particles
            renders(result)        # what loads, renders (outside the trace: it compiles)


SEEDS = {".ply": PLY, ".off": OFF, ".stl": STL_ASCII}


def test_the_seeds_are_valid():
    assert read_tri(TRI, "seed.tri").triangle_count == 5
    assert len(read_mesh(OBJ, "seed.obj", ".obj").triangles) == 12
    assert len(read_mesh(PLY, "seed.ply", ".ply").triangles) == 2
    assert read_scene_file(TOML, "seed.toml", SCENES_DIR).triangle_count == 12 + 2 * 8 * 4


@FUZZ
@given(mutated(TRI))
def test_fuzz_tri_mutated(data):
    only_reader_errors(lambda d: read_tri(d, "fuzz.tri"), data)


@FUZZ
@given(st.binary(max_size=400))
def test_fuzz_tri_random_bytes(data):
    only_reader_errors(lambda d: read_tri(d, "fuzz.tri"), data)


@FUZZ
@given(mutated(OBJ))
def test_fuzz_obj_mutated(data):
    only_reader_errors(lambda d: read_mesh(d, "fuzz.obj", ".obj"), data)


@FUZZ
@given(st.binary(max_size=400))
def test_fuzz_obj_random_bytes(data):
    only_reader_errors(lambda d: read_mesh(d, "fuzz.obj", ".obj"), data)


@settings(FUZZ, max_examples=40)
@given(st.data(), st.sampled_from([".ply", ".off", ".stl"]))
def test_fuzz_other_mesh_formats(data, ext):
    # each format mutated from a valid file of its own, so the fuzz gets past the header
    only_reader_errors(lambda d: read_mesh(d, f"fuzz{ext}", ext), data.draw(mutated(SEEDS[ext])))


@settings(FUZZ, max_examples=40)
@given(st.binary(max_size=60).map(lambda tail: STL_BINARY[:84] + tail))
def test_fuzz_binary_stl(data):
    only_reader_errors(lambda d: read_mesh(d, "fuzz.stl", ".stl"), data)


@pytest.mark.parametrize("ext, seed", [(".off", OFF), (".stl", STL_ASCII), (".stl", STL_BINARY)])
def test_the_fuzz_seeds_are_valid_files(ext, seed):
    assert len(read_mesh(seed, f"seed{ext}", ext).triangles) >= 1


@FUZZ
@given(mutated(TOML))
def test_fuzz_toml_mutated(data):
    only_reader_errors(lambda d: read_scene_file(d, "fuzz.toml", SCENES_DIR), data)


@FUZZ
@given(st.binary(max_size=400))
def test_fuzz_toml_random_bytes(data):
    only_reader_errors(lambda d: read_scene_file(d, "fuzz.toml", SCENES_DIR), data)


@pytest.mark.parametrize("count", [b"1000000000000", b"18446744073709551617", b"999999999999999999999999"])
def test_huge_counts_in_headers_take_no_memory(count):
    only_reader_errors(lambda d: read_tri(d, "x.tri"), TRI.replace(b"\n5\n", b"\n" + count + b"\n"))
    only_reader_errors(lambda d: read_mesh(d, "x.ply", ".ply"), PLY.replace(b"vertex 4", b"vertex " + count))
    only_reader_errors(lambda d: read_mesh(d, "x.off", ".off"), b"OFF\n" + count + b" 1 0\n0 0 0\n3 0 0 0\n")
    stl = b"\0" * 80 + (int(count) % 2 ** 32).to_bytes(4, "little") + b"\0" * 100
    only_reader_errors(lambda d: read_mesh(d, "x.stl", ".stl"), stl)


@settings(FUZZ, max_examples=30)
@given(st.data())
@pytest.mark.parametrize("name", list(TARGETS))
def test_fuzz_every_reader_mutated_from_its_seed(name, data):
    read, seed = TARGETS[name]
    only_reader_errors(read, data.draw(mutated(seed)))


@pytest.mark.parametrize("name", list(TARGETS))
def test_every_fuzz_seed_renders(name):
    read, seed = TARGETS[name]
    with small_budgets():
        assert renders(read(seed)) == ("animated" if name in ("keys", "emitters", "bvh", "actors")
                                       else "rendered")


# The systems' keys, mutated at the value level two times in three (a seeded
# mutation per example, so a failure names its seed); animated scenes drawn at three moments.
@settings(FUZZ, max_examples=25)
@given(st.integers(0, 2**32 - 1))
@pytest.mark.parametrize("name", SYSTEMS)
def test_fuzz_the_systems_keys(name, seed):
    import random
    data = mutate_any(random.Random(seed), name, TARGETS[name][1])
    assert check(name, data) in ("refused", "rendered", "animated", "no views", "budget")



# --------------------------------------------------------------------------- reach and corpus

# The least share of seeded mutations that must get through the reader and render, per target:
# about half of what 150 mutations each reached when this was written (tri 25 %, obj 17 %,
# ply 9 %, ply-binary 5 %, off 9 %, stl-ascii 23 %, stl-binary 17 %, toml 11 %, views 67 %).
# A reader that refused everything would keep every other invariant; this one it breaks.
MIN_RENDERED = {"tri": 0.12, "obj": 0.08, "ply": 0.04, "ply-binary": 0.02, "off": 0.04,
                "stl-ascii": 0.10, "stl-binary": 0.08, "toml": 0.05, "views": 0.30}
REACH_CASES = 150


@pytest.mark.parametrize("name", list(MIN_RENDERED))
def test_mutated_inputs_reach_the_renderer(name):
    import random
    from collections import Counter
    from fuzz_targets import check, mutate
    _, seed = TARGETS[name]
    rng = random.Random(f"share:{name}")
    outcomes = Counter(check(name, mutate(rng, seed)) for _ in range(REACH_CASES))
    share = outcomes["rendered"] / REACH_CASES
    assert share >= MIN_RENDERED.get(name, 0.02), f"{name}: {dict(outcomes)}"


CORPUS = TESTS / "fuzz_corpus"


def _corpus():
    import json
    manifest = json.loads((CORPUS / "manifest.json").read_text())
    return sorted(manifest.items())


@pytest.mark.parametrize("file,expected", _corpus(), ids=[f for f, _ in _corpus()])
def test_the_fuzz_corpus_keeps_its_outcomes(file, expected):
    """Inputs the fuzzers found interesting (each target's mutations that rendered, and one
    per distinct reason of refusal), kept in the repository: each must still hold the
    invariant and give the outcome it gave when it was kept."""
    from fuzz_targets import check
    assert check(expected["target"], (CORPUS / file).read_bytes()) == expected["outcome"]

"""The long fuzz run of the readers, run once by hand, not in CI:

    python tests/fuzz_long.py --cases 100000 --budget 4500 --out fuzz-long.json

Every reader of ``tests/fuzz_targets.py`` gets ``--cases`` inputs (seeded mutations of its
seed file; one in ten is random bytes; the systems' targets — textures, keys,
emitters, primitives — get their parsed values edited two times in three), each held to the invariant there: a ReaderError with a
one-line message, or a scene whose views all render in both projections. The readers take
turns, a batch at a time, so that a time budget cut short still covers every reader. The
counts per reader and outcome go to ``--out`` (rewritten after every batch), and every input
that breaks the invariant is saved beside it with its traceback.
"""

from __future__ import annotations

import argparse
import json
import random
import sys
import time
import traceback
from collections import Counter
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))          # fuzz_targets
sys.path.insert(0, str(Path(__file__).resolve().parent.parent))   # this checkout's core

from fuzz_targets import TARGETS, check, mutate_any  # noqa: E402

BATCH = 500


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--cases", type=int, default=100_000, help="inputs per reader")
    p.add_argument("--budget", type=float, default=3600.0, help="seconds for the whole run")
    p.add_argument("--seed", type=int, default=15)
    p.add_argument("--out", default="fuzz-long.json")
    p.add_argument("--batch", type=int, default=BATCH, help="cases per reader per turn")
    p.add_argument("--readers", default=",".join(TARGETS),
                   help="which targets, comma-separated (runs may be split across processes)")
    args = p.parse_args()
    names = [n for n in args.readers.split(",") if n]
    unknown = set(names) - set(TARGETS)
    if unknown:
        p.error(f"unknown readers {sorted(unknown)}; known: {', '.join(TARGETS)}")
    out = Path(args.out)
    failures = out.with_suffix(".failures")
    rngs = {name: random.Random(f"{args.seed}:{name}") for name in names}
    counts = {name: Counter() for name in names}
    spent = {name: 0.0 for name in names}
    start = time.monotonic()
    while time.monotonic() - start < args.budget:
        pending = [n for n in names if sum(counts[n].values()) < args.cases]
        if not pending:
            break
        for name in pending:
            t0 = time.monotonic()
            for _ in range(min(args.batch, args.cases - sum(counts[name].values()))):
                counts[name][_one(name, rngs[name], failures)] += 1
            spent[name] += time.monotonic() - t0
        _write(out, args, counts, spent, time.monotonic() - start)
    _write(out, args, counts, spent, time.monotonic() - start)
    print(json.dumps(json.loads(out.read_text())["readers"], indent=1))
    return 1 if any(c["FAILED"] for c in counts.values()) else 0


def _one(name: str, rng: random.Random, failures: Path) -> str:
    seed = TARGETS[name][1]
    data = (bytes(rng.randint(0, 255) for _ in range(rng.randint(0, 400)))
            if rng.random() < 0.1 else mutate_any(rng, name, seed))
    try:
        return check(name, data)
    except Exception:                        # the invariant broken: keep the input
        failures.mkdir(exist_ok=True)
        stem = failures / f"{name}-{rng.getrandbits(32):08x}"
        stem.with_suffix(".bin").write_bytes(data)
        stem.with_suffix(".txt").write_text(traceback.format_exc())
        return "FAILED"


def _write(out: Path, args, counts, spent, elapsed: float) -> None:
    readers = {name: {**dict(c), "cases": sum(c.values()),
                      "ms per case": round(1e3 * spent[name] / max(sum(c.values()), 1), 2)}
               for name, c in counts.items()}
    out.write_text(json.dumps({"cases per reader": args.cases, "seed": args.seed,
                               "seconds": round(elapsed, 1), "readers": readers}, indent=1))


if __name__ == "__main__":
    sys.exit(main())

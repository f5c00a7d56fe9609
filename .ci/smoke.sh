#!/usr/bin/env bash
# The smoke set for one Python, on a clean clone: does the program install from wheels alone
# and run there?
#
#   .ci/smoke.sh PYTHON [REPO]     e.g. .ci/smoke.sh /root/.pyenv/versions/3.13.0/bin/python
#
# REPO (default: this checkout) is cloned into a temporary folder (its committed HEAD: commit
# first), with ../shared beside it linked when REPO has one. Then, each phase timed:
#   install  a venv; `pip install --only-binary :all: REPO[test]` with CC=false CXX=false:
#            every dependency from a wheel, no compiler (pip builds only the project itself,
#            which is pure Python)
#   cli      the installed `fvd-viewer --help` and `--version`, and `python -m app --version`
#   warmup   the installed program's `warmup`: every kernel compiled from nothing on this
#            Python, one worker process a core, the stamp written
#   render   every shipped scene (app.distribution.warmup.shipped_scenes) at 64x48 by the installed
#            program, each PNG checked to exist, be 64x48 and not be one flat colour
#   window   the real-window smoke tests under Xvfb (first frame, clicks, menus, keys,
#            screenshots), from the clone, with the test extras installed on this Python
# FVD_SMOKE_PHASES="cli render" runs only those (install always runs). Any failure exits
# non-zero with a line naming the Python and the phase. FVD_SMOKE_KEEP=1 keeps the folder.
# Beside another job (.ci/run runs this beside the main test suite, which keeps one of two
# cores busy on average): FVD_SMOKE_NICE=N runs every phase but the window's at that niceness,
# so that it takes the cores the other job leaves idle; FVD_SMOKE_WINDOW_AFTER=FILE holds the
# window phase until FILE exists, so that its real window never shares the cores with the
# other job's windows and compiles.
set -euo pipefail

python=${1:?usage: .ci/smoke.sh PYTHON [REPO]}
repo=$(cd "${2:-$(dirname "$0")/..}" && pwd)
phases=${FVD_SMOKE_PHASES:-cli warmup render window}
name=$("$python" -c 'import sys; print("Python %d.%d.%d" % sys.version_info[:3])' 2>/dev/null) \
  || { echo "smoke: $python: not a working Python" >&2; exit 1; }
work=$(mktemp -d "${TMPDIR:-/tmp}/fvd-smoke.XXXXXX")
[ -n "${FVD_SMOKE_KEEP:-}" ] || trap 'rm -rf "$work"' EXIT
clone=$work/fvd-viewer
venv=$work/venv
py=$venv/bin/python
phase=set-up
started=$SECONDS
phase_started=$SECONDS
times=()

niced() { if [ -n "${FVD_SMOKE_NICE:-}" ]; then nice -n "$FVD_SMOKE_NICE" "$@"; else "$@"; fi; }
fail() { echo "smoke: $name ($python): $phase failed${1:+: $1}" >&2; exit 1; }
trap 'fail "exit status $? at line $LINENO"' ERR
begin() { phase=$1; phase_started=$SECONDS; echo "smoke: $name: $phase ..."; }
end() {
  local took=$((SECONDS - phase_started))
  times+=("$phase ${took}s")
  echo "smoke: $name: $phase done in ${took}s"
}

begin clone
git clone -q "$repo" "$clone"
if [ -d "$repo/../shared" ]; then ln -s "$(cd "$repo/../shared" && pwd)" "$work/shared"; fi
end

begin install
niced "$python" -m venv "$venv"
# No compiler: a dependency without a wheel for this Python fails here, loudly.
CC=false CXX=false PIP_ONLY_BINARY=:all: niced "$py" -m pip install -q --disable-pip-version-check \
  "$clone[test]" || fail "a dependency has no wheel for $name (see pip's message above)"
end

cd "$work"                          # not the clone: the installed program is the one that runs
if [[ " $phases " == *" cli "* ]]; then
  begin cli
  "$venv/bin/fvd-viewer" --help > help.txt
  grep -q '^usage: fvd-viewer ' help.txt || fail "--help does not name fvd-viewer"
  for v in "$venv/bin/fvd-viewer --version" "$py -m app --version"; do
    out=$($v)
    [[ "$out" == "fvd-viewer "* && "$out" == *"Python ${name#Python }"* ]] \
      || fail "'$v' printed: $out"
  done
  end
fi

if [[ " $phases " == *" warmup "* ]]; then
  begin warmup                      # every kernel compiled on all cores, as `make` does
  niced "$venv/bin/fvd-viewer" -q warmup > warmup.txt || { tail -20 warmup.txt; fail "the warm-up"; }
  end
fi

if [[ " $phases " == *" render "* ]]; then
  begin render
  # the scene list from the installed package; the files from the clone (a scene may read
  # ../../shared beside the repository, as the bunny does)
  mapfile -t scenes < <("$py" -c 'from app.distribution.warmup import shipped_scenes
print(*(p.name for p in shipped_scenes()), sep="\n")')
  [ ${#scenes[@]} -gt 0 ] || fail "no shipped scenes in the installed package"
  mkdir -p png
  for scene in "${scenes[@]}"; do
    t=$SECONDS
    [ -f "$clone/scenes/$scene" ] || fail "$scene is in the package but not in scenes/"
    # a .tri file's camera is in pixels (its own 500 x 500): another size shows only a corner
    size=(--size 64x48); want=64x48
    if [[ "$scene" == *.tri ]]; then size=(); want=any; fi
    niced "$venv/bin/fvd-viewer" render "$clone/scenes/$scene" "${size[@]}" \
      --out "png/${scene%.*}.png" > /dev/null 2> render.err || { cat render.err; fail "render $scene"; }
    # a picture may be one flat colour only where the program said what it left out (a
    # scene lit only by an emitter, drawn by a renderer that does not light with one)
    "$py" - "png/${scene%.*}.png" render.err "$want" <<'EOF' || fail "render $scene: the PNG is missing or blank"
import sys
from PIL import Image
with Image.open(sys.argv[1]) as image:
    low, high = zip(*image.convert("RGB").getextrema())
    assert sys.argv[3] == "any" or image.size == (64, 48), image.size
    said = "not drawn:" in open(sys.argv[2], encoding="utf-8", errors="replace").read()
    assert low != high or said, f"one flat colour {low}, and no word of what was not drawn"
EOF
    echo "  $scene $((SECONDS - t))s"
  done
  end
fi

if [[ " $phases " == *" window "* ]]; then
  if [ -n "${FVD_SMOKE_WINDOW_AFTER:-}" ]; then
    waited=$SECONDS
    until [ -e "$FVD_SMOKE_WINDOW_AFTER" ]; do
      [ $((SECONDS - waited)) -lt 3600 ] || fail "$FVD_SMOKE_WINDOW_AFTER did not appear within an hour"
      sleep 2
    done
    echo "smoke: $name: waited $((SECONDS - waited))s for the other job before the window phase"
  fi
  begin window
  cd "$clone"
  # The tests run the clone's code, whose kernel cache is its own folder. The installed
  # package is the same code, and a cached kernel is keyed by its code's digest, not its
  # path (core/jit.py): take the kernels the warm-up phase compiled rather than compile them
  # again (about 100 s of this phase; -I finds the installed package, not the clone in the
  # working folder). Without them (no warm-up phase), compile what the tests' two scenes
  # draw first: the window would wait for its worker processes otherwise.
  site=$("$py" -I -c 'import core, pathlib; print(pathlib.Path(core.__file__).parent.parent)')
  (cd "$site" && find core app -path '*/__pycache__/*' \( -name '*.nbi' -o -name '*.nbc' \
    -o -name 'warm.json' \) -print0 | tar --null -cf - -T -) | tar -xf -
  if [ ! -f core/__pycache__/warm.json ]; then
    "$py" -m app.distribution.warmup --only whitted.toml --only house.toml > warmup-window.txt \
      || { tail -20 warmup-window.txt; fail "the window tests' warm-up"; }
  fi
  CI=true "$py" -m pytest -q -p no:cacheprovider \
    tests/app/viewer/test_window.py tests/app/viewer/test_window_newcomer.py \
    -k "click_menu_and_keys_under_xvfb or screenshots_follow_the_naming_rule" \
    || fail "the window tests"
  end
fi

echo "smoke: $name: passed in $((SECONDS - started))s (${times[*]})"

#!/usr/bin/env bash
# Which of the dependencies have a wheel for each Python and platform: the table in
# docs/install.md. `pip download --only-binary :all: --no-deps` per package, Python and
# platform (the newest release that satisfies pyproject's lower bound and has a wheel).
#   .ci/wheels.sh [PIP]    one line a check: package, python, platform, the wheel or MISSING
# PIP defaults to `python3 -m pip`; a recent pip knows the newest platform tags.
set -euo pipefail
pip=(${1:-python3 -m pip})
pythons=(${FVD_WHEEL_PYTHONS:-3.11 3.12 3.13 3.14})
platforms=(${FVD_WHEEL_PLATFORMS:-manylinux_2_28_x86_64 manylinux_2_28_aarch64 macosx_14_0_arm64 win_amd64})
# the runtime dependencies (pyproject) and what they pull in that is not pure Python, then
# the anim extra's (av, dask[distributed]) and distributed's compiled dependencies
packages=(${FVD_WHEEL_PACKAGES:-"numpy>=1.26" "numba>=0.59" llvmlite "moderngl>=5.10" glcontext
          "glfw>=2.6" "imgui-bundle>=1.92" "Pillow>=10" "trimesh>=4" "matplotlib>=3.7" contourpy
          kiwisolver fonttools cycler pyparsing python-dateutil packaging
          "threadpoolctl>=3" "av>=12" "dask>=2024.1" distributed msgpack psutil tornado pyyaml
          markupsafe})
tags() {           # pip takes manylinux_2_28_x86_64 literally: name every glibc up to 2.28
  case "$1" in
    manylinux_2_28_*) local arch=${1#manylinux_2_28_} v
                      for v in $(seq 17 28); do printf -- '--platform manylinux_2_%s_%s ' "$v" "$arch"; done
                      printf -- '--platform manylinux2014_%s' "$arch" ;;
    *) printf -- '--platform %s' "$1" ;;        # pip widens macosx_14_0_arm64 itself
  esac
}
check() {                               # package python platform
  local dir; dir=$(mktemp -d)
  # shellcheck disable=SC2046
  if "${pip[@]}" download -q --only-binary :all: --no-deps --python-version "$2" \
       $(tags "$3") -d "$dir" "$1" >/dev/null 2>&1; then
    printf '%s\t%s\t%s\t%s\n' "$1" "$2" "$3" "$(ls "$dir")"
  else
    printf '%s\t%s\t%s\tMISSING\n' "$1" "$2" "$3"
  fi
  rm -rf "$dir"
}
for package in "${packages[@]}"; do
  for python in "${pythons[@]}"; do
    for platform in "${platforms[@]}"; do
      check "$package" "$python" "$platform" &
      while [ "$(jobs -rp | wc -l)" -ge 6 ]; do wait -n; done
    done
  done
done
wait

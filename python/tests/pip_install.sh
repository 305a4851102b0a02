#!/usr/bin/env bash
# `pip install .` as the README gives it, into a fresh virtual environment
# (Debian's packages visible, as its numpy and pytest), then the Python tests
# against the installed package. Exit 77 (skipped, reason printed) when PyPI
# cannot be reached for the build backend.
#   pip_install.sh <source dir> <python3> [NAME=VALUE...]
# Each NAME=VALUE is a CMake definition for the package's build (passed to
# scikit-build-core as cmake.define.NAME), e.g. a compiler launcher.
# PLSA_PIP_BUILD_DIR, if set: the package's build directory (made afresh,
# removed at the end; default: scikit-build-core's temporary one).
set -euo pipefail
src=$1
python=$2
shift 2
defines=()
for d in "$@"; do defines+=("--config-settings=cmake.define.$d"); done
work=$(mktemp -d)
build_dir=${PLSA_PIP_BUILD_DIR:-}
if [ -n "$build_dir" ]; then
  rm -rf "$build_dir"
  defines+=("--config-settings=build-dir=$build_dir")
fi
trap 'rm -rf "$work" ${build_dir:+"$build_dir"}' EXIT
"$python" -m venv --system-site-packages "$work/venv"
pip=("$work/venv/bin/pip" --disable-pip-version-check --no-input --quiet)
# The build backend from PyPI first, so a network failure reads as one.
if ! "${pip[@]}" install "scikit-build-core>=0.10" "pybind11>=2.10" > "$work/backend.log" 2>&1; then
  echo "skipped: pip cannot install the build backend (scikit-build-core, pybind11) from PyPI:"
  tail -n 3 "$work/backend.log"
  exit 77
fi
"${pip[@]}" install --no-build-isolation "${defines[@]}" "$src"
cd "$work"  # away from the source tree, so `import plsa` finds the installed package
unset PYTHONPATH
"$work/venv/bin/python" -c 'import plsa, plsa_lcm, sys; print("installed", plsa.__version__, "at", plsa.__file__)'
"$work/venv/bin/python" -m pytest -q -p no:cacheprovider "$src/python/tests"

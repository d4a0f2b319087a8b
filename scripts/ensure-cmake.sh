#!/usr/bin/env bash
# Source this file: makes `cmake` available for the osqp 0.6 crate's build.
# Uses a system cmake when present, otherwise installs the `cmake` wheel from PyPI
# (works on a machine that has only Python with pip, no root needed).
if ! command -v cmake >/dev/null 2>&1; then
  if ! python3 -c 'import cmake' >/dev/null 2>&1; then
    echo "contactlab set-up: installing cmake from PyPI (python3 -m pip install cmake)" >&2
    python3 -m pip install --quiet cmake || { echo "could not install cmake with pip" >&2; return 1 2>/dev/null || exit 1; }
  fi
  CMAKE_BIN_DIR=$(python3 -c 'import cmake; print(cmake.CMAKE_BIN_DIR)')
  export PATH="$CMAKE_BIN_DIR:$PATH"
fi
# CMake 4 refuses the old cmake_minimum_required of OSQP 0.6's sources without this.
export CMAKE_POLICY_VERSION_MINIMUM=3.5

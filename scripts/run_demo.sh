#!/usr/bin/env bash
# The README's demo after the build: `biomechreg` with no argument (phantom -> estimation -> report into
# ./biomechreg-demo of the current directory), then the plot of its sweep and convergence history.
# Run by `scripts/setup.sh demo` and, unchanged, by the ctest `readme_demo`, so the README's command is tested.
# Usage: scripts/run_demo.sh BUILD_DIR
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
build="${1:?usage: $0 BUILD_DIR}"
"$build/bin/biomechreg"
/usr/bin/python3 "$root/scripts/plot_register.py" biomechreg-demo/register

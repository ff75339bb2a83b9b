#!/bin/sh
# Accuracy of the high-precision reference and of the double engine against it
# (docs/guide/reference.md): scenario 2 to 300 s at 50 and 100 digits,
# scenario 1 to 10 s at 20 and 40 digits (the first 1000 switches and more).
# Prints event-count agreement, the largest relative event-time difference, the
# end-state difference, and the double engine's event-time error against the
# 2N-digit run over the matched prefix and where it parts. About 10 s on 2 cores.
#
# Usage: bench/reference_check.sh [BUILD_DIR]   (default: build)
set -eu
here=$(cd "$(dirname "$0")/.." && pwd)
build=${1:-"$here/build"}
check="$build/hsnc_reference_check"
[ -x "$check" ] || { echo "reference_check.sh: no $check (cmake --build $build --target hsnc_reference_check)" >&2; exit 2; }
"$check" "$here/models/seed-scenario-2.toml" 300 50
echo
"$check" "$here/models/seed-scenario-1.toml" 10 20

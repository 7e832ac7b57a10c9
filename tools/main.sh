#!/usr/bin/env bash
# The main job: build, then estimate a simulated run of the paper's Case 1
# end to end and print the identified type, its decision time and theta.
set -euo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
cd "$root"
source tools/setup.sh
cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build build -j "$(nproc)" >/dev/null
exec build/tools/demo/hstpf-demo "$@"

#!/usr/bin/env bash
# The HIL stage of tools/test.sh: the replay test through hstpfd on vcan0
# (natively where vcan exists, else in the QEMU VM of tests/hil/vm).
set -euo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)
exec "$root/tests/hil/with_vcan.sh" "$root/tests/hil/hil_replay.sh" "${1:-$root/build}"

#!/usr/bin/env bash
# Proves tests/hil/with_vcan.sh gives a working vcan0 (natively or in the VM):
# python-can exchanges a frame between two SocketCAN buses, and a C program
# built here on the host exchanges one over raw AF_CAN sockets.
#
#   tests/hil/vm/smoke.sh          (HSTPF_VCAN_MODE=vm forces the VM)
#
# Python: $HSTPF_PYTHON, else the active virtualenv, else the repo's .venv,
# else python3; it needs python-can.
set -euo pipefail

here=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
repo=$(cd "$here/../../.." && pwd)

if [ -n "${HSTPF_PYTHON:-}" ]; then python=$HSTPF_PYTHON
elif [ -n "${VIRTUAL_ENV:-}" ] && [ -x "$VIRTUAL_ENV/bin/python" ]; then python=$VIRTUAL_ENV/bin/python
elif [ -x "$repo/.venv/bin/python" ]; then python=$repo/.venv/bin/python
else python=$(command -v python3)
fi
"$python" -c 'import can' 2>/dev/null ||
    { echo "smoke: $python has no python-can (pip install python-can)" >&2; exit 1; }

tmp=$(mktemp -d "${TMPDIR:-/tmp}/hstpf-smoke.XXXXXX")
trap 'rm -rf "$tmp"' EXIT

# Built on the host, run in the VM: the same binaries the HIL tests will use.
cc -std=c99 -Wall -Wextra -Werror -O1 -o "$tmp/cansock" "$here/cansock.c"

cat >"$tmp/pycan.py" <<'EOF'
import socket
import can

# The plain socket module first: fails loudly if the kernel has no AF_CAN.
socket.socket(socket.AF_CAN, socket.SOCK_RAW, socket.CAN_RAW).close()
with can.Bus(interface="socketcan", channel="vcan0") as tx, \
        can.Bus(interface="socketcan", channel="vcan0") as rx:
    sent = can.Message(arbitration_id=0x123, data=[1, 2, 3, 4, 5, 6, 7, 8], is_extended_id=False)
    tx.send(sent)
    got = rx.recv(timeout=2.0)
    assert got is not None, "no frame received on vcan0"
    assert got.arbitration_id == sent.arbitration_id and got.data == sent.data, got
    print(f"smoke: python-can {can.__version__} exchanged {got.arbitration_id:#x} "
          f"{got.data.hex()} on vcan0")
EOF

# One VM boot runs both checks; the script counts them for CI's log.
cat >"$tmp/inside.sh" <<'EOF'
passed=0 failed=0
if "$1" "$2/pycan.py"; then passed=$((passed + 1)); else failed=$((failed + 1)); fi
if "$2/cansock" vcan0; then passed=$((passed + 1)); else failed=$((failed + 1)); fi
echo "smoke: $passed passed, $failed failed"
[ "$failed" = 0 ]
EOF

"$repo/tests/hil/with_vcan.sh" bash "$tmp/inside.sh" "$python" "$tmp"

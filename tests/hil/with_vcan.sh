#!/usr/bin/env bash
# Runs a command with working virtual CAN interfaces (vcan0 by default):
# natively when this machine's kernel has vcan, else inside a QEMU virtual
# machine (tests/hil/vm/run.sh). Exit status is the command's.
#
#   tests/hil/with_vcan.sh CMD [ARGS...]
#
# HSTPF_VCAN_MODE=auto|native|vm (default auto) forces a path;
# HSTPF_VCAN_IFACES="vcan0 vcan1" names the interfaces (default vcan0);
# HSTPF_VM_* variables tune the VM (see tests/hil/vm/run.sh).
set -euo pipefail

here=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
export PATH=$PATH:/usr/sbin:/sbin   # ip and modprobe live there
export HSTPF_VCAN_IFACES=${HSTPF_VCAN_IFACES:-vcan0}

log() { printf 'with_vcan: %s\n' "$*" >&2; }
[ $# -gt 0 ] || { echo "usage: $0 CMD [ARGS...]" >&2; exit 2; }

# Runs as root directly, else through password-less sudo if there is one.
as_root() {
    if [ "$(id -u)" = 0 ]; then "$@"
    elif command -v sudo >/dev/null && sudo -n true 2>/dev/null; then sudo -n "$@"
    else "$@"
    fi
}

# True when every interface exists (creating it if it can) and is up.
native_vcan() {
    command -v ip >/dev/null || return 1
    local ifc
    for ifc in $HSTPF_VCAN_IFACES; do
        if ! ip link show dev "$ifc" >/dev/null 2>&1; then
            as_root ip link add dev "$ifc" type vcan 2>/dev/null || {
                command -v modprobe >/dev/null && as_root modprobe vcan 2>/dev/null &&
                    as_root ip link add dev "$ifc" type vcan 2>/dev/null
            } || return 1
        fi
        # Already up is fine even when we may not change it.
        ip -o link show dev "$ifc" | grep -q '[<,]UP[,>]' ||
            as_root ip link set up dev "$ifc" 2>/dev/null || return 1
    done
}

mode=${HSTPF_VCAN_MODE:-auto}
case $mode in
    native)
        native_vcan || { log "error: no native $HSTPF_VCAN_IFACES (HSTPF_VCAN_MODE=native)"; exit 125; }
        ;;
    vm) ;;
    auto) native_vcan && mode=native || mode=vm ;;
    *) log "error: HSTPF_VCAN_MODE must be auto, native or vm"; exit 2 ;;
esac

if [ "$mode" = native ]; then
    log "native $HSTPF_VCAN_IFACES on this machine's kernel"
    exec "$@"
fi
log "no native vcan here: running in a QEMU VM with $HSTPF_VCAN_IFACES (tests/hil/vm/run.sh)"
exec "$here/vm/run.sh" -- "$@"

#!/bin/bash
# Runs inside the VM, chrooted into the host's root (started by the VM's /init).
# Recreates the caller's situation from the job folder that run.sh wrote
# (environment, working directory, umask, argv), brings up the vcan
# interfaces, runs the command and leaves its exit code in "rc".
# The output goes to files in the job folder, which the host streams.
set -uo pipefail
job=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
exec </dev/null >>"$job/stdout" 2>>"$job/stderr"

finish() {
    # rc appears whole or not at all: the host reads it after the VM is gone.
    printf '%s\n' "$1" >"$job/rc.tmp" && mv "$job/rc.tmp" "$job/rc"
    exit 0
}

# shellcheck disable=SC1091  # written by run.sh
source "$job/env"
umask "$(<"$job/umask")"

# The host's iproute2 knows "type vcan"; look beyond PATH, which may lack sbin.
ip=$(PATH=/usr/sbin:/sbin:/usr/bin:/bin command -v ip) || {
    echo "hstpf-vm: no 'ip' (iproute2) on the host" >&2
    finish 125
}
for ifc in ${HSTPF_VCAN_IFACES:-vcan0}; do
    if ! { "$ip" link add dev "$ifc" type vcan && "$ip" link set up "$ifc"; }; then
        echo "hstpf-vm: cannot create $ifc in the VM" >&2
        finish 125
    fi
done

cwd=$(<"$job/cwd")
cd "$cwd" || { echo "hstpf-vm: cannot cd to $cwd in the VM" >&2; finish 125; }
mapfile -d '' -t argv <"$job/argv"
"${argv[@]}"
finish $?

#!/usr/bin/env bash
# Runs a command inside a throw-away QEMU virtual machine whose kernel has
# SocketCAN, with vcan0 up, on the host's own file system (shared over 9p
# and chrooted into), in the caller's working directory and environment.
#
#   tests/hil/vm/run.sh [--timeout SEC] -- CMD [ARGS...]
#
# Exit status: CMD's; 124 if the VM ran out of time; 125 if the VM failed
# before CMD finished. Variables: HSTPF_VM_TIMEOUT (default 1200 s),
# HSTPF_VM_DEBUG=1 (show the VM's console), HSTPF_VM_KEEP=1 (keep the job
# folder), HSTPF_VM_ACCEL=tcg|kvm, HSTPF_VM_MEM (MiB, default 1024),
# HSTPF_VM_CPUS (default 2), HSTPF_VCAN_IFACES (default "vcan0"),
# HSTPF_VM_CACHE (see prepare.sh).
set -euo pipefail

here=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)

log() { printf 'hstpf-vm: %s\n' "$*" >&2; }
die() { log "error: $*"; exit 125; }
usage() { echo "usage: $0 [--timeout SEC] -- CMD [ARGS...]" >&2; exit 2; }

timeout_s=${HSTPF_VM_TIMEOUT:-1200}
while [ $# -gt 0 ]; do
    case $1 in
        --timeout) [ $# -ge 2 ] || usage; timeout_s=$2; shift 2 ;;
        --timeout=*) timeout_s=${1#--timeout=}; shift ;;
        --) shift; break ;;
        -h|--help) usage ;;
        *) break ;;
    esac
done
[ $# -gt 0 ] || usage
[[ $timeout_s =~ ^[0-9]+$ ]] && [ "$timeout_s" -gt 0 ] || die "bad timeout: $timeout_s"
debug=${HSTPF_VM_DEBUG:-0}

img=$("$here/prepare.sh") || die "preparing the VM image failed"

# The job folder is how host and guest talk: the guest sees it at the same
# path. Its path goes on the kernel command line, so no blanks in it.
job=$(mktemp -d "${TMPDIR:-/tmp}/hstpf-vm.XXXXXX")
case $job in *[[:space:]]*) rm -rf "$job"; job=$(mktemp -d /tmp/hstpf-vm.XXXXXX) ;; esac

qpid='' tails=()
# shellcheck disable=SC2329  # called by the EXIT trap
cleanup() {
    local rc=$?
    trap - EXIT INT TERM
    [ -n "$qpid" ] && kill "$qpid" 2>/dev/null && wait "$qpid" 2>/dev/null
    for p in "${tails[@]}"; do kill "$p" 2>/dev/null || true; done
    if [ "${HSTPF_VM_KEEP:-0}" = 1 ]; then log "job folder kept: $job"; else rm -rf "$job"; fi
    exit "$rc"
}
trap cleanup EXIT
trap 'log "interrupted"; exit 130' INT
trap 'log "terminated"; exit 143' TERM

# The caller's exported environment, bash-quoted, less what describes this
# very shell or cannot be assigned.
for name in $(compgen -e); do
    case $name in
        PWD|OLDPWD|SHLVL|_|UID|EUID|PPID|SHELLOPTS|BASHOPTS|BASH_VERSINFO|GROUPS) continue ;;
    esac
    printf 'export %s=%q\n' "$name" "${!name}"
done >"$job/env"
printf '%s' "$PWD" >"$job/cwd"
umask >"$job/umask"
printf '%s\0' "$@" >"$job/argv"
cp "$here/guest.sh" "$job/guest.sh"
: >"$job/stdout"; : >"$job/stderr"; : >"$job/console.log"

# TCG (software emulation) by default: it works everywhere. KVM is opt-in
# only: where /dev/kvm is nested and broken the guest hangs instead of
# failing, so no automatic fallback could be trusted.
case ${HSTPF_VM_ACCEL:-tcg} in
    tcg) accel=(-accel tcg) ;;
    kvm) accel=(-accel kvm) ;;
    *) die "HSTPF_VM_ACCEL must be tcg or kvm" ;;
esac
append="console=ttyS0 panic=-1 hstpf.job=$job hstpf.9pcache=${HSTPF_VM_9P_CACHE:-loose}"
if [ "$debug" = 1 ]; then append+=" hstpf.debug=1"; else append+=" quiet"; fi

# -cpu max: host binaries (numpy...) may need SSE4/AVX, which qemu64 lacks.
# The console goes to a file, not the terminal: no raw-mode tty, Ctrl-C stays ours.
start=$(date +%s)
timeout -k 10 "$timeout_s" qemu-system-x86_64 \
    -nographic -no-reboot -m "${HSTPF_VM_MEM:-1024}" -smp "${HSTPF_VM_CPUS:-2}" \
    "${accel[@]}" -cpu max \
    -kernel "$img/vmlinuz" -initrd "$img/initramfs.cpio.gz" -append "$append" \
    -virtfs local,path=/,mount_tag=hostroot,security_model=none,multidevs=remap \
    -virtfs "local,path=$job,mount_tag=hstpfjob,security_model=none" \
    -nic none -monitor none -serial "file:$job/console.log" \
    </dev/null >"$job/qemu.log" 2>&1 &
qpid=$!

# The firmware's terminal escapes, dropped from the console shown.
unescape='s/\x1b\[[0-9;?]*[a-zA-Z]//g; s/\x1bc//g'

# Stream CMD's output live; tail stops by itself once qemu is gone.
tail -n +1 -F -s 0.2 --pid="$qpid" "$job/stdout" 2>/dev/null &
tails+=($!)
tail -n +1 -F -s 0.2 --pid="$qpid" "$job/stderr" >&2 2>/dev/null &
tails+=($!)
if [ "$debug" = 1 ]; then
    tail -n +1 -F -s 0.2 --pid="$qpid" "$job/console.log" 2>/dev/null |
        sed -u "$unescape; s/^/[vm] /" >&2 &
    tails+=($!)
fi

qrc=0
wait "$qpid" || qrc=$?
qpid=
for p in "${tails[@]}"; do wait "$p" 2>/dev/null || true; done
tails=()
[ "$debug" = 1 ] && log "VM ran $(($(date +%s) - start)) s (qemu status $qrc)"

if [ -f "$job/rc" ]; then
    exit "$(<"$job/rc")"
fi
if [ "$qrc" = 124 ] || [ "$qrc" = 137 ]; then
    log "error: the VM did not finish within ${timeout_s} s (--timeout / HSTPF_VM_TIMEOUT)"
    status=124
else
    log "error: the VM stopped before the command finished (qemu status $qrc)"
    status=125
fi
if [ "$debug" != 1 ]; then
    log "last lines of the VM console (HSTPF_VM_DEBUG=1 shows it all):"
    tail -n 30 "$job/console.log" | sed "$unescape; s/^/[vm] /" >&2
fi
[ -s "$job/qemu.log" ] && sed 's/^/[qemu] /' "$job/qemu.log" >&2
exit "$status"

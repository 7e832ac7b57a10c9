#!/usr/bin/env bash
# Builds, once, what tests/hil/vm/run.sh boots: the Debian kernel that
# linux-image-amd64 depends on (unpacked, never installed on this host) and a
# busybox initramfs carrying the modules for virtio/9p and SocketCAN/vcan.
#
# Idempotent: the image lives in $HSTPF_VM_CACHE (default ~/.cache/hstpf-vm)
# under a name hashed from its inputs (kernel package and version, busybox,
# this script, the guest's /init); a warm run only compares that hash.
# Prints the image folder on stdout; messages go to stderr.
set -euo pipefail

here=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
home=${HOME:-$(getent passwd "$(id -u)" | cut -d: -f6)}
cache=${HSTPF_VM_CACHE:-$home/.cache/hstpf-vm}
export PATH=$PATH:/usr/sbin:/sbin

log() { printf 'hstpf-vm: %s\n' "$*" >&2; }
die() { log "error: $*"; exit 1; }
trap 'log "error: prepare.sh failed at line $LINENO"' ERR

# Modules the guest needs, roots only: their dependencies are read from each
# module's own modinfo (the .deb ships no modules.dep; depmod runs at install).
# The order follows the environment notes. Optional ones may be missing or
# built in, in which case they are reported and skipped.
required_mods=(virtio_pci 9pnet_virtio 9p can can_raw vcan)
optional_mods=(can_dev can_bcm can_gw can_isotp)

is_root() { [ "$(id -u)" = 0 ]; }

apt_install() {
    # Another developer's apt may hold the dpkg lock: wait for it, not fail.
    DEBIAN_FRONTEND=noninteractive apt-get install -y -q --no-install-recommends \
        -o DPkg::Lock::Timeout=300 "$@" </dev/null >&2 && return 0
    apt-get update -q -o DPkg::Lock::Timeout=300 </dev/null >&2
    DEBIAN_FRONTEND=noninteractive apt-get install -y -q --no-install-recommends \
        -o DPkg::Lock::Timeout=300 "$@" </dev/null >&2
}

# --- host tools --------------------------------------------------------------
missing=()
command -v qemu-system-x86_64 >/dev/null || missing+=(qemu-system-x86)
# Only the static busybox can run in an initramfs with no libc.
[ "$(dpkg-query -W -f='${Status}' busybox-static 2>/dev/null)" = "install ok installed" ] ||
    missing+=(busybox-static)
command -v cpio >/dev/null || missing+=(cpio)
command -v ip >/dev/null || missing+=(iproute2)   # runs vcan setup inside the guest
if [ ${#missing[@]} -gt 0 ]; then
    if is_root; then
        log "installing host packages: ${missing[*]}"
        apt_install "${missing[@]}" || die "apt-get install ${missing[*]} failed"
    else
        die "missing host packages; run: sudo apt-get install ${missing[*]}"
    fi
fi
command -v apt-get >/dev/null || die "needs a Debian host (apt-get) to fetch the kernel"
busybox=$(dpkg-query -L busybox-static | grep -m1 '/busybox$')
[ -x "$busybox" ] || die "busybox-static installed but its binary was not found"

# --- which kernel ------------------------------------------------------------
# The metapackage pins its kernel: "Depends: linux-image-6.1.0-NN-amd64 (= V)".
# One apt-cache call (about 0.5 s) gives both name and version.
kernel_pkg() {
    apt-cache show --no-all-versions linux-image-amd64 2>/dev/null |
        sed -n 's/^Depends:.*\(linux-image-[^ ,]*\) (= \([^)]*\)).*/\1 \2/p' | head -n1
}
kpkg_ver=$(kernel_pkg)
if [ -z "$kpkg_ver" ] && is_root; then
    log "package lists do not know linux-image-amd64; running apt-get update"
    apt-get update -q -o DPkg::Lock::Timeout=300 </dev/null >&2 || true
    kpkg_ver=$(kernel_pkg)
fi
kpkg=${kpkg_ver% *} kver=${kpkg_ver#* }

mkdir -p "$cache"
if [ -z "$kpkg" ] || [ -z "$kver" ]; then
    # Offline or no package lists: an image built earlier is still good.
    if [ -e "$cache/current/ready" ]; then
        log "warning: cannot resolve linux-image-amd64 (no apt lists?); using the cached image"
        readlink -f "$cache/current"
        exit 0
    fi
    die "cannot resolve linux-image-amd64 with apt-cache; run 'apt-get update' first"
fi

# --- up to date? ---------------------------------------------------------------
inputs=$(
    printf '%s\n' "$kpkg=$kver" "${required_mods[*]}" "${optional_mods[*]}"
    sha256sum "$busybox" "$here/prepare.sh" "$here/init" | cut -d' ' -f1
)
id=$(printf '%s' "$inputs" | sha256sum | cut -c1-16)
img=$cache/img-$id

# One builder at a time; a second caller waits, then finds the image ready.
exec 9>"$cache/.lock"
flock 9
if [ -e "$img/ready" ]; then
    [ "$(readlink "$cache/current" 2>/dev/null)" = "img-$id" ] || ln -sfn "img-$id" "$cache/current"
    printf '%s\n' "$img"
    exit 0
fi

# --- build -------------------------------------------------------------------
log "building VM image $id ($kpkg $kver) in $cache"
work=$(mktemp -d "$cache/.build.XXXXXX")
trap 'rm -rf "$work"' EXIT

# Keep the .deb (70 MB) so that a change to this script does not download again.
deb_dir=$cache/deb
mkdir -p "$deb_dir"
deb=$(find "$deb_dir" -maxdepth 1 -name "${kpkg}_${kver//:/%3a}_*.deb" -print -quit)
if [ -z "$deb" ]; then
    rm -f "$deb_dir"/*.deb
    dl_opts=()
    # Root's apt drops to user _apt, which cannot write here; it would only warn.
    is_root && dl_opts=(-o APT::Sandbox::User=root)
    if ! (cd "$work" && apt-get download -q "${dl_opts[@]}" "$kpkg=$kver" </dev/null >&2); then
        # Offline with a newer kernel in the lists: the older image still works.
        if [ -e "$cache/current/ready" ]; then
            log "warning: apt-get download $kpkg=$kver failed; using the cached image"
            readlink -f "$cache/current"
            exit 0
        fi
        die "apt-get download $kpkg=$kver failed"
    fi
    mv "$work"/*.deb "$deb_dir"/
    deb=$(find "$deb_dir" -maxdepth 1 -name '*.deb' -print -quit)
fi

dpkg-deb -x "$deb" "$work/pkg"
# Newer Debian kernels may ship under usr/lib: look in both (one is missing).
moddir=$( (find "$work/pkg/lib/modules" "$work/pkg/usr/lib/modules" -mindepth 1 -maxdepth 1 \
    -type d 2>/dev/null || true) | head -n1)
[ -n "$moddir" ] || die "no lib/modules in $deb"
krel=${moddir##*/}
vmlinuz=$( (find "$work/pkg/boot" "$work/pkg/usr/lib/linux-image-$krel" -maxdepth 1 \
    -name "vmlinuz*" 2>/dev/null || true) | head -n1)
[ -n "$vmlinuz" ] || die "no vmlinuz in $deb"

# Module name -> file; names compare with '-' and '_' as equal, as the kernel does.
declare -A ko_path=() builtin=() seen=()
while IFS= read -r f; do
    b=${f##*/}; b=${b%%.ko*}; ko_path[${b//-/_}]=$f
done < <(find "$moddir/kernel" -name '*.ko*')
if [ -f "$moddir/modules.builtin" ]; then
    while IFS= read -r f; do
        b=${f##*/}; b=${b%%.ko*}; builtin[${b//-/_}]=1
    done <"$moddir/modules.builtin"
fi

ko_cat() {
    case $1 in
        *.ko) cat "$1" ;;
        *.ko.xz) xz -dc "$1" ;;
        *.ko.zst) zstd -dcq "$1" ;;
        *.ko.gz) gzip -dc "$1" ;;
        *) die "unknown module compression: $1" ;;
    esac
}

order=() report=()
# Depth-first: every module is listed after what it depends on.
visit() {
    local n=${1//-/_} optional=$2 d deps
    [ -z "${seen[$n]:-}" ] || return 0
    seen[$n]=1
    if [ -n "${builtin[$n]:-}" ]; then report+=("built in: $n"); return 0; fi
    if [ -z "${ko_path[$n]:-}" ]; then
        [ "$optional" = 1 ] || die "module $n is neither built into $krel nor shipped as a module"
        report+=("missing (optional, skipped): $n"); return 0
    fi
    deps=$(ko_cat "${ko_path[$n]}" | tr '\0' '\n' | sed -n 's/^depends=//p' | tr ',' ' ')
    for d in $deps; do visit "$d" "$optional"; done
    order+=("$n")
}
for m in "${required_mods[@]}"; do visit "$m" 0; done
for m in "${optional_mods[@]}"; do visit "$m" 1; done

root=$work/initramfs
mkdir -p "$root"/{bin,sbin,usr/bin,usr/sbin,etc,proc,sys,dev,host,tmp,lib/modules}
install -m 0755 "$busybox" "$root/bin/busybox"
install -m 0755 "$here/init" "$root/init"
for n in "${order[@]}"; do
    # busybox insmod takes plain ELF only: decompress here.
    ko_cat "${ko_path[$n]}" >"$root/lib/modules/$n.ko"
done
printf '%s\n' "${order[@]}" >"$root/etc/hstpf-modules"
printf '%s\n' "kernel: $kpkg $kver ($krel)" "insmod order: ${order[*]}" ${report[@]+"${report[@]}"} \
    >"$root/etc/hstpf-modules.report"

out=$work/img
mkdir -p "$out"
cp "$vmlinuz" "$out/vmlinuz"
(cd "$root" && find . -print0 | LC_ALL=C sort -z |
    cpio --null -o -H newc --owner=0:0 --quiet) | gzip -6 >"$out/initramfs.cpio.gz"
cp "$root/etc/hstpf-modules.report" "$out/modules.txt"
printf '%s\n' "$inputs" >"$out/inputs"
touch "$out/ready"

rm -rf "$img"
mv "$out" "$img"
ln -sfn "img-$id" "$cache/current"
# Older images: not needed any more (a VM already booted has them in memory).
find "$cache" -maxdepth 1 -name 'img-*' ! -name "img-$id" -exec rm -rf {} +
log "VM image ready: $img"
sed 's/^/hstpf-vm:   /' "$img/modules.txt" >&2
printf '%s\n' "$img"

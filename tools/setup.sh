#!/usr/bin/env bash
# Installs what hstpf needs on a Debian machine: build tools, cmocka, the
# Cortex-M4F cross compiler, QEMU and busybox for the vcan VM, clang with its
# sanitizer/libFuzzer runtime, gcc-multilib (-m32), gcovr, and a Python
# venv (.venv) with the tools. Idempotent and quiet when all is there.
# Sourced by tools/test.sh and tools/main.sh.
set -euo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)

debs=(cmake ninja-build gcc libc6-dev make pkg-config libcmocka-dev
      gcc-arm-none-eabi libnewlib-arm-none-eabi binutils-arm-none-eabi
      qemu-system-x86 qemu-system-arm busybox-static cpio kmod iproute2
      python3 python3-venv python3-pip
      clang libclang-rt-14-dev gcc-multilib gcovr)
missing=()
for p in "${debs[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
  echo "setup: installing ${missing[*]}"
  sudo_cmd=()
  [ "$(id -u)" -eq 0 ] || sudo_cmd=(sudo)
  "${sudo_cmd[@]}" apt-get update -qq
  DEBIAN_FRONTEND=noninteractive "${sudo_cmd[@]}" apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
fi

venv="$root/.venv"
if [ ! -x "$venv/bin/python" ]; then
  echo "setup: creating $venv"
  python3 -m venv "$venv"
fi
stamp="$venv/.hstpf-setup"
want=$({ cat "$root/tools/pyproject.toml" 2>/dev/null || true; } | sha1sum | cut -c1-12)
if [ ! -f "$stamp" ] || [ "$(cat "$stamp")" != "$want" ]; then
  echo "setup: installing Python packages into $venv"
  "$venv/bin/pip" install -q --upgrade pip
  "$venv/bin/pip" install -q numpy matplotlib pytest python-can cantools
  if [ -f "$root/tools/pyproject.toml" ]; then
    "$venv/bin/pip" install -q -e "$root/tools"
  fi
  echo "$want" > "$stamp"
fi
export PATH="$venv/bin:$PATH"
export VIRTUAL_ENV="$venv"

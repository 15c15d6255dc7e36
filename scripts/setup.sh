#!/usr/bin/env bash
# One idempotent set-up step shared by README.md and .ci/run.
#  1. installs what a fresh Debian machine lacks: the Vulkan loader, lavapipe
#     (Mesa 25 from the backports suite where the machine's apt sources can
#     reach it, else the distribution's Mesa), the validation layers, shaderc;
#  2. merges Debian's static shaderc/glslang/SPIRV-Tools archives into one
#     real combined archive (Debian's libshaderc.so is underlinked), which
#     .cargo/config.toml points the shaderc crate at.
# No package registry's host is written here: the backports entry is derived
# from the machine's own apt sources.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
sudo=""
[ "$(id -u)" -eq 0 ] || sudo="sudo"

pkgs=(libvulkan1 mesa-vulkan-drivers vulkan-validationlayers libshaderc-dev glslang-dev spirv-tools)
missing=()
for p in "${pkgs[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done

add_backports() {
  local src=/etc/apt/sources.list.d/debian.sources dst=/etc/apt/sources.list.d/glint-backports.sources
  [ -f "$dst" ] && return 0
  [ -f "$src" ] || return 1
  . /etc/os-release
  [ -n "${VERSION_CODENAME:-}" ] || return 1
  # The first stanza that serves the release itself (not -security/-updates).
  awk -v rel="$VERSION_CODENAME" -v bp="$VERSION_CODENAME-backports" '
    BEGIN { RS=""; FS="\n" }
    {
      ok = 0
      for (i = 1; i <= NF; i++) if ($i ~ "^Suites:" && $i ~ ("[ \t]" rel "([ \t]|$)")) ok = 1
      if (ok && !done) {
        for (i = 1; i <= NF; i++) {
          if ($i ~ "^Suites:") print "Suites: " bp
          else if ($i !~ /^#/) print $i
        }
        done = 1
      }
    }' "$src" | $sudo tee "$dst.tmp" >/dev/null
  if grep -q '^URIs:' "$dst.tmp"; then $sudo mv "$dst.tmp" "$dst"; else $sudo rm -f "$dst.tmp"; return 1; fi
}

if [ "${#missing[@]}" -gt 0 ]; then
  echo "setup: installing ${missing[*]}" >&2
  export DEBIAN_FRONTEND=noninteractive
  add_backports || echo "setup: no backports suite derivable; using the distribution's Mesa" >&2
  $sudo apt-get update -qq
  . /etc/os-release
  policy=$(apt-cache policy mesa-vulkan-drivers 2>/dev/null || true)
  if grep -q "${VERSION_CODENAME:-none}-backports" <<<"$policy"; then
    # Mesa and its LLVM move together; install the Vulkan driver from backports.
    $sudo apt-get install -y -qq -t "$VERSION_CODENAME-backports" mesa-vulkan-drivers >/dev/null \
      || echo "setup: backports Mesa failed; falling back to the distribution's" >&2
  fi
  $sudo apt-get install -y -qq "${missing[@]}" >/dev/null
fi

# Combined shaderc archive for the shaderc crate (see ../shared/notes/toolchain.md).
out="$root/target/shaderc"
lib=/usr/lib/$(gcc -print-multiarch 2>/dev/null || echo x86_64-linux-gnu)
if [ ! -f "$out/libshaderc_combined.a" ]; then
  mkdir -p "$out"
  # ar's MRI script cannot quote a path with spaces: the archive is made in
  # a fresh temporary folder and moved into the checkout.
  tmp=$(mktemp -d)
  script="create $tmp/libshaderc_combined.a"
  for a in shaderc_combined glslang MachineIndependent GenericCodeGen OSDependent OGLCompiler SPIRV HLSL SPIRV-Tools-opt SPIRV-Tools; do
    [ -f "$lib/lib$a.a" ] && script+=$'\n'"addlib $lib/lib$a.a"
  done
  script+=$'\nsave\nend'
  ar -M <<<"$script"
  mv "$tmp/libshaderc_combined.a" "$out/libshaderc_combined.a.tmp"
  mv "$out/libshaderc_combined.a.tmp" "$out/libshaderc_combined.a"
  rm -rf "$tmp"
fi
echo "setup: ok ($(dpkg-query -W -f='${Version}' mesa-vulkan-drivers) lavapipe)" >&2

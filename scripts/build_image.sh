#!/usr/bin/env bash
# Build the robonix-nav container image locally, with no container registry: a Debian base rootfs made
# by debootstrap (--variant=minbase, from the mirror apt already uses, plus the host's CA certificates)
# imported into podman, then docker/Dockerfile on top, installing the project's wheel and its pinned
# dependencies from a wheelhouse built on the host. Every build and run uses --pull=never.
#
#   scripts/build_image.sh                 # image robonix-nav2 (ROBONIX_NAV2_IMAGE), base built if missing
#   ROBONIX_BASE_REBUILD=1 scripts/build_image.sh   # rebuild the base rootfs from nothing
#   ROBONIX_IMAGE_ARCH=arm64 scripts/build_image.sh # Jetson: foreign-arch rootfs + arm64 wheels; needs
#                                                     qemu-user-static binfmt on an x86 host (untested here)
#
# Caches (same machine, reused between runs; everything is rebuilt when they are absent):
#   $RBNX_IMAGE_CACHE (default ${XDG_CACHE_HOME:-~/.cache}/robonix-nav/image): debootstrap's .deb cache
#   and the wheelhouse of pinned dependencies.
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
cd "$root"
engine="${ROBONIX_CONTAINER_ENGINE:-podman}"
image="${ROBONIX_NAV2_IMAGE:-robonix-nav2}"
host_arch="$(dpkg --print-architecture 2>/dev/null || echo amd64)"
arch="${ROBONIX_IMAGE_ARCH:-$host_arch}"
suite="${ROBONIX_BASE_SUITE:-bookworm}"
base="${ROBONIX_BASE_IMAGE:-localhost/robonix-base:$suite-$arch}"
cache="${RBNX_IMAGE_CACHE:-${XDG_CACHE_HOME:-$HOME/.cache}/robonix-nav/image}"
mkdir -p "$cache/debs" "$cache/wheelhouse-$arch"
log="$(mktemp "${TMPDIR:-/tmp}/robonix-build-image.XXXXXX.log")"  # removed on success
# Quiet unless a step fails; then its output ends up on stderr.
step() { "$@" >>"$log" 2>&1 || { echo "build_image.sh: failed: $*" >&2; tail -30 "$log" >&2; exit 1; }; }

if ! command -v "$engine" >/dev/null 2>&1; then
  if [ "$engine" = podman ]; then bash "$root/scripts/install_engine.sh"; else
    echo "build_image.sh: container engine '$engine' not found" >&2; exit 1; fi
fi

t0=$(date +%s%N)
stamp() { local ms=$(( ($(date +%s%N) - t0) / 1000000 )); printf 'build_image.sh: %-40s %d.%01d s\n' "$1" $((ms / 1000)) $((ms % 1000 / 100)); }

# The Debian mirror apt already uses (deb822 .sources first, then one-line sources.list).
mirror() {
  local m=""
  if compgen -G "/etc/apt/sources.list.d/*.sources" >/dev/null; then
    m="$(awk '/^URIs:/ {print $2; exit}' /etc/apt/sources.list.d/*.sources)"
  fi
  if [ -z "$m" ] && [ -r /etc/apt/sources.list ]; then
    m="$(awk '$1 == "deb" && $0 !~ /security/ {for (i = 2; i <= NF; i++) if ($i ~ /^[a-z]+:\/\//) {print $i; exit}}' /etc/apt/sources.list)"
  fi
  echo "${m:-http://deb.debian.org/debian}"
}

build_base() {
  command -v debootstrap >/dev/null 2>&1 || bash "$root/scripts/install_engine.sh"
  local rootfs
  rootfs="$(mktemp -d "${TMPDIR:-/tmp}/robonix-rootfs.XXXXXX")"
  # shellcheck disable=SC2064  # expand now: the trap must remove this very directory
  trap "rm -rf '$rootfs'" EXIT
  step debootstrap --variant=minbase --arch="$arch" --cache-dir="$cache/debs" \
    --include=python3,python3-venv,ca-certificates "$suite" "$rootfs" "$(mirror)"
  # pip inside the image must trust what the host trusts (a TLS-inspecting proxy, for one).
  if [ -r /etc/ssl/certs/ca-certificates.crt ]; then
    cp /etc/ssl/certs/ca-certificates.crt "$rootfs/etc/ssl/certs/ca-certificates.crt"
  fi
  rm -rf "${rootfs:?}"/var/cache/apt/archives/*.deb "${rootfs:?}"/var/lib/apt/lists/*
  tar -C "$rootfs" --numeric-owner -c . | "$engine" import -q \
    --change 'ENV PATH=/usr/local/sbin:/usr/local/bin:/usr/sbin:/usr/bin:/sbin:/bin' \
    --change 'ENV LANG=C.UTF-8' --change 'CMD ["/bin/bash"]' - "$base" >/dev/null
  rm -rf "$rootfs"
  trap - EXIT
}

if [ "${ROBONIX_BASE_REBUILD:-0}" = 1 ] || ! "$engine" image exists "$base" 2>/dev/null; then
  build_base
  stamp "base rootfs $base"
fi

# The project's wheel and its pinned dependencies (constraints.txt), collected on the host so the
# image build needs no network; pip's own cache makes a rebuild cheap.
py="${PYTHON:-python3}"
ctx="$(mktemp -d "${TMPDIR:-/tmp}/robonix-image-context.XXXXXX")"  # own folder: parallel builds never mix
# shellcheck disable=SC2064  # expand now: remove this very directory
trap "rm -rf '$ctx'" EXIT
mkdir -p "$ctx/wheels"
wheel="$(PYTHON="$py" bash "$root/scripts/build_wheel.sh" "$ctx/wheels" 2>>"$log")" \
  || { echo "build_image.sh: wheel build failed" >&2; tail -30 "$log" >&2; exit 1; }
if [ "$arch" = "$host_arch" ]; then
  step "$py" -m pip wheel -q -c "$root/constraints.txt" -w "$cache/wheelhouse-$arch" "$wheel"
else
  pyarch="$([ "$arch" = arm64 ] && echo aarch64 || echo "$arch")"
  step "$py" -m pip download -q -c "$root/constraints.txt" -d "$cache/wheelhouse-$arch" --only-binary=:all: \
    --python-version 3.11 --implementation cp --platform "manylinux2014_$pyarch" \
    --platform "manylinux_2_28_$pyarch" --platform "manylinux_2_34_$pyarch" "$wheel"
fi
# pip also drops the project's own wheel into the wheelhouse: keep only dependencies there, or a stale
# copy of the project would overwrite the fresh one below.
rm -f "$cache/wheelhouse-$arch"/robonix_nav-*.whl
cp -n "$cache/wheelhouse-$arch"/*.whl "$ctx/wheels/"
cp "$root/constraints.txt" "$ctx/"
mkdir -p "$ctx/docker"
cp "$root"/docker/* "$ctx/docker/"
stamp "wheel + wheelhouse"

# docker format keeps the HEALTHCHECK (OCI images have none)
fmt=(); [ "$engine" = podman ] && fmt=(--format docker)
step "$engine" build "${fmt[@]}" --pull=never --network=none --platform "linux/$arch" -t "$image" \
  --build-arg "BASE_IMAGE=$base" -f "$ctx/docker/Dockerfile" "$ctx"
stamp "image $image"
rm -f "$log"

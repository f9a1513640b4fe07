#!/usr/bin/env bash
# Install the container engine used for the robonix-nav image when it is absent: Debian's podman with
# runc as its runtime (crun cannot drive the hybrid cgroup layout of some hosts) and default ulimits that
# fit under a low hard open-file limit. Needs root (apt). Idempotent: a working engine is left alone,
# only the drop-in config is (re)written.
set -euo pipefail
conf_dir=/etc/containers/containers.conf.d
conf="$conf_dir/50-robonix-nav.conf"

need=()
command -v podman >/dev/null 2>&1 || need+=(podman)
command -v runc >/dev/null 2>&1 || need+=(runc)
command -v debootstrap >/dev/null 2>&1 || need+=(debootstrap)
[ -r /etc/ssl/certs/ca-certificates.crt ] || need+=(ca-certificates)
if [ "${#need[@]}" -gt 0 ]; then
  if [ "$(id -u)" -ne 0 ]; then
    echo "install_engine.sh: missing ${need[*]}; run as root (apt-get install ${need[*]})" >&2
    exit 1
  fi
  echo "install_engine.sh: installing ${need[*]}"
  export DEBIAN_FRONTEND=noninteractive
  # Another apt run on a shared machine holds the lock for a while: wait for it instead of failing.
  apt-get -o DPkg::Lock::Timeout=900 update -qq
  apt-get -o DPkg::Lock::Timeout=900 install -y -qq --no-install-recommends "${need[@]}" \
    uidmap fuse-overlayfs slirp4netns netavark aardvark-dns iptables >/dev/null
fi

# Hard nofile limit of the host may be low (20000 here): podman's default (1048576) would fail to apply.
hard_nofile="$(ulimit -Hn)"
[ "$hard_nofile" = unlimited ] && hard_nofile=1048576
nofile=$(( hard_nofile < 20000 ? hard_nofile : 20000 ))
if [ -w /etc ] || [ "$(id -u)" -eq 0 ]; then
  mkdir -p "$conf_dir"
  cat > "$conf.tmp" <<CONF
# written by robonix-nav scripts/install_engine.sh
[containers]
default_ulimits = ["nofile=$nofile:$nofile", "nproc=32768:32768"]

[engine]
runtime = "runc"
CONF
  mv "$conf.tmp" "$conf"
fi
podman --version

#!/usr/bin/env bash
# Installs, with one apt-get run, the system tools the test command needs beyond Rust and what
# it fetches itself (Embree): a one-node Slurm (scripts/test-slurm.sh), OpenImageIO's oiiotool
# (scripts/test-exr-metadata.sh), Chromium and Node.js (scripts/test-browser.sh), python3.
# A no-op when all are present; needs root (or sudo) and apt-get otherwise.
#
#   scripts/install-test-tools.sh
set -euo pipefail
have() { command -v "$1" >/dev/null 2>&1 || [ -x "/usr/sbin/$1" ]; }
# command → Debian package (the lean Slurm set: no recommended plugins; docs/cluster.md).
pairs=(
  slurmctld:slurmctld slurmd:slurmd sbatch:slurm-client sinfo:slurm-client
  scontrol:slurm-client munged:munge python3:python3 oiiotool:openimageio-tools
  chromium:chromium node:nodejs npm:npm
)
packages=()
for p in "${pairs[@]}"; do
  tool=${p%%:*} package=${p#*:}
  if ! have "$tool" && [[ " ${packages[*]} " != *" $package "* ]]; then
    packages+=("$package")
  fi
done
if [ ${#packages[@]} -eq 0 ]; then
  echo "install-test-tools: everything present"
  exit 0
fi
echo "install-test-tools: installing ${packages[*]} with apt-get"
command -v apt-get >/dev/null || {
  echo "install-test-tools: apt-get not found; install ${packages[*]} by hand" >&2
  exit 1
}
sudo=()
if [ "$(id -u)" -ne 0 ]; then
  command -v sudo >/dev/null || { echo "install-test-tools: not root and no sudo: install ${packages[*]} as root" >&2; exit 1; }
  sudo=(sudo)
fi
export DEBIAN_FRONTEND=noninteractive
start=$SECONDS
"${sudo[@]}" apt-get update -qq
"${sudo[@]}" apt-get install -y -qq --no-install-recommends "${packages[@]}" >/dev/null
echo "install-test-tools: installed in $((SECONDS - start)) s"

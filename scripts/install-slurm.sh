#!/usr/bin/env bash
# Install what scripts/test-slurm.sh needs (slurmctld, slurmd, sbatch/sinfo/scontrol, munged,
# and python3 for its EXR comparison) from the distribution's packages with apt-get; a no-op
# when they are all present already.
#
#   scripts/install-slurm.sh            # as root (or with sudo on PATH)
#
# The lean package set below (8 packages on Debian bookworm, no recommended plugins) is enough
# for a one-node cluster with proctrack/linuxproc and task/none; `apt-get install slurm-wlm
# munge` works too but installs 42 (docs/cluster.md has the times). Exits non-zero when apt-get
# is unavailable or the install fails.
set -euo pipefail

have() {
  command -v "$1" >/dev/null 2>&1 || [ -x "/usr/sbin/$1" ]
}

missing=()
for tool in slurmctld slurmd sbatch sinfo scontrol munged python3; do
  have "$tool" || missing+=("$tool")
done
packages=(slurmctld slurmd slurm-client munge)
have python3 || packages+=(python3)
if [ ${#missing[@]} -eq 0 ]; then
  echo "install-slurm: slurm, munge and python3 already installed"
  exit 0
fi
echo "install-slurm: missing ${missing[*]}; installing with apt-get"
if ! command -v apt-get >/dev/null 2>&1; then
  echo "install-slurm: apt-get not found; install slurmctld, slurmd, slurm-client and munge by hand" >&2
  exit 1
fi
as_root=()
if [ "$(id -u)" -ne 0 ]; then
  if command -v sudo >/dev/null 2>&1; then
    as_root=(sudo)
  else
    echo "install-slurm: must run as root (or with sudo available)" >&2
    exit 1
  fi
fi
export DEBIAN_FRONTEND=noninteractive
"${as_root[@]}" apt-get update -q
"${as_root[@]}" env DEBIAN_FRONTEND=noninteractive apt-get install -y -q --no-install-recommends \
  "${packages[@]}"
for tool in slurmctld slurmd sbatch sinfo scontrol munged python3; do
  if ! have "$tool"; then
    echo "install-slurm: $tool still missing after the install" >&2
    exit 1
  fi
done
echo "install-slurm: done"

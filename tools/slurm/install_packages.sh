#!/bin/bash
# Install what start_single_node.sh needs from Debian (12: SLURM 22.05): slurmctld, slurmd,
# slurm-client and munge, without recommends and without starting any service.
#
#     tools/slurm/install_packages.sh                  # as root
#     tools/slurm/install_packages.sh --accounting     # also slurmdbd and mariadb-server
#
# Prints the packages it newly installed (dependencies included), one per line, so that
# they can be removed again (`apt-get purge -y $(cat list)`); nothing if all were present.
# Exit status 3 with one line on stderr when they cannot be installed (not root, no
# apt-get, no network to the mirror).
set -euo pipefail
PKGS="slurmctld slurmd slurm-client munge"
if [ "${1:-}" = --accounting ]; then PKGS="$PKGS slurmdbd mariadb-server"; fi
fail() { echo "$*" >&2; exit 3; }

[ "$(id -u)" -eq 0 ] || fail "not root (apt-get needs root)"
command -v apt-get >/dev/null && command -v dpkg-query >/dev/null || fail "no apt-get/dpkg (not a Debian system)"
installed() { dpkg-query -W -f='${Package} ${db:Status-Abbrev}\n' 2>/dev/null | awk '$2 == "ii" {print $1}' | sort; }
missing=$(for p in $PKGS; do installed | grep -qx "$p" || echo "$p"; done)
[ -n "$missing" ] || exit 0
before=$(installed)

# no service may start at install: the daemons belong to start_single_node.sh (a container
# without systemd has no init to start them either; Debian's invoke-rc.d asks policy-rc.d)
policy=/usr/sbin/policy-rc.d
made_policy=false
if [ ! -e "$policy" ]; then
    printf '#!/bin/sh\nexit 101\n' > "$policy" && chmod +x "$policy" && made_policy=true
fi
log=$(mktemp)
trap '$made_policy && rm -f "$policy"; rm -f "$log"' EXIT
export DEBIAN_FRONTEND=noninteractive
apt_install() {
    # shellcheck disable=SC2086
    apt-get install -y -q --no-install-recommends -o DPkg::Lock::Timeout=300 $missing >> "$log" 2>&1
}
if ! apt_install; then
    # package lists missing or stale (a fresh container): update them once and retry
    apt-get update -q -o DPkg::Lock::Timeout=300 >> "$log" 2>&1 || true
    apt_install || fail "apt-get install $(echo $missing) failed: $(grep -E '^(E|W):' "$log" | tail -n 1)"
fi
comm -13 <(echo "$before") <(installed)

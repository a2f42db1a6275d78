#!/usr/bin/env bash
# Start Fast DDS's discovery server from the project's .venv: the wheels'
# fast-discovery-server binary with the libraries it needs (the venv's
# lib/ and the Fast DDS wheel's bundled ones), which a plain shell does
# not find. Arguments go to it as they are, e.g.:
#   bash scripts/discovery_server.sh -i 0 -l 192.168.1.10 -p 11811
#   bash scripts/discovery_server.sh --help
# It opens sockets on the addresses given: see doc/deployment.md.
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
VENV="$ROOT/.venv"
[ -x "$VENV/bin/fast-discovery-server" ] || {
    echo "discovery_server: no $VENV/bin/fast-discovery-server: run bash scripts/setup_venv.sh" >&2
    exit 2
}
LIBS="$VENV/lib"
for bundled in "$VENV"/lib/python3*/site-packages/ros_fastrtps.libs; do
    LIBS="$LIBS:$bundled"
done
export LD_LIBRARY_PATH="$LIBS${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}"
exec "$VENV/bin/fast-discovery-server" "$@"

# Sourced by the peer benchmarks: sets `here` (the repository) and `venv` (a virtual
# environment with numpy, scipy and python-control from PyPI: target/peers-venv, or
# $ERA_PEERS_VENV, made on first use), checks for /usr/bin/time and enters the repository.
here=$(cd "$(dirname "${BASH_SOURCE[1]}")/.." && pwd)
venv=${ERA_PEERS_VENV:-$here/target/peers-venv}
if [ ! -x "$venv/bin/python" ]; then
  python3 -m venv "$venv"
  "$venv/bin/pip" install -q numpy scipy control
fi
command -v /usr/bin/time >/dev/null || { echo "needs /usr/bin/time (apt-get install time)" >&2; exit 2; }
cd "$here"

# Sourced by bench/oma_peers.sh: sets `here` (the repository) and `venv`, a virtual
# environment with the output-only (OMA) peers from PyPI, pinned to the versions the
# tables were measured with: pyOMA-2 (dagghe/pyOMA2) and koma-python (knutankv/koma),
# with numpy, scipy, matplotlib and scikit-learn as they require. It lives in
# target/oma-venv, or $ERA_OMA_VENV, and is made on first use (a few minutes; about
# 1.3 GB, as pyOMA-2 brings pyvista, vtk and jupyter). Both peers run headless: matplotlib's Agg
# backend, pyvista off screen, no progress bars.
here=$(cd "$(dirname "${BASH_SOURCE[1]}")/.." && pwd)
venv=${ERA_OMA_VENV:-$here/target/oma-venv}
oma_peer_versions="pyOMA-2==1.4.3 koma-python==1.3.6"
if ! "$venv/bin/python" -c 'import pyoma2, koma.oma, koma.clustering' 2>/dev/null; then
  python3 -m venv "$venv"
  "$venv/bin/pip" install -q $oma_peer_versions
fi
export MPLBACKEND=Agg PYVISTA_OFF_SCREEN=true TQDM_DISABLE=1
cd "$here"

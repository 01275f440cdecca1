# Sourced by the scripts (not run): builds the `era` binary in release and sets
#   target_dir  cargo's target directory: CARGO_TARGET_DIR, a .cargo/config target-dir,
#               or the workspace's target/ (what `cargo metadata` reports)
#   era         the path of the release binary in it
# The caller must have cd'd into the workspace first.
cargo build --release -q -p era-cli
target_dir=$(cargo metadata --format-version 1 --no-deps 2>/dev/null |
  sed -n 's/.*"target_directory":"\([^"]*\)".*/\1/p')
target_dir=${target_dir:-${CARGO_TARGET_DIR:-target}}
era=$target_dir/release/era
[ -x "$era" ] || { echo "no era binary at $era after cargo build" >&2; exit 2; }

#!/usr/bin/env bash
# Builds the playground into a folder any static host serves (default: target/web/site,
# under $CARGO_TARGET_DIR when that is set):
#
#     web/build.sh [OUT]
#
# The library compiled to WebAssembly without sym's JIT and mech's threads (profile
# `web`), its JS glue written by crates/web/bindgen (wasm-bindgen's generator of the
# version crates/web pins, as a library: what `wasm-bindgen --target web --no-typescript`
# writes, without installing wasm-bindgen-cli), this folder's page, and the examples as
# examples.json.
set -euo pipefail
cd "$(dirname "$0")/.."
target=$(realpath -m "${CARGO_TARGET_DIR:-target}")
out=$(realpath -m "${1:-$target/web/site}")

rustup target list --installed 2>/dev/null | grep -qx wasm32-unknown-unknown \
    || rustup target add wasm32-unknown-unknown
cargo build -q -p lagrange-web --target wasm32-unknown-unknown --profile web
rm -rf "$out"
mkdir -p "$out"
# A workspace of its own with its own lock file, in the dev profile: unoptimized it
# builds in about a minute from scratch and writes the glue in about 3 s (optimized,
# 3 minutes and 0.4 s).
cargo run -q --locked --manifest-path crates/web/bindgen/Cargo.toml --target-dir "$target/bindgen" -- \
    "$target/wasm32-unknown-unknown/web/lagrange_web.wasm" "$out/pkg"
cp web/index.html web/playground.css web/playground.js web/worker.js "$out/"
python3 - "$out/examples.json" <<'PY'
import json, pathlib, re, sys
root = pathlib.Path("examples")
files = {p.relative_to(root).as_posix(): p.read_text() for p in sorted(root.rglob("*.toml"))}
models = [{"path": path} for path, text in files.items() if re.search(r"^coordinates", text, re.M)]
pathlib.Path(sys.argv[1]).write_text(json.dumps({"models": models, "files": files}))
PY
echo "$out"

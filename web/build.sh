#!/usr/bin/env bash
# Builds the playground into a folder any static host serves (default: target/web/site):
#
#     web/build.sh [OUT]
#
# The library compiled to WebAssembly without sym's JIT and mech's threads (profile
# `web`), the JS glue from wasm-bindgen-cli of the version crates/web pins (installed with
# cargo if missing), this folder's page, and the examples as examples.json.
set -euo pipefail
cd "$(dirname "$0")/.."
out=$(realpath -m "${1:-target/web/site}")

rustup target list --installed 2>/dev/null | grep -qx wasm32-unknown-unknown \
    || rustup target add wasm32-unknown-unknown
version=$(sed -n 's/^wasm-bindgen = "=\([0-9.]*\)".*/\1/p' crates/web/Cargo.toml)
if [ "$(wasm-bindgen --version 2>/dev/null | cut -d' ' -f2)" != "$version" ]; then
    # --locked first; the lock file of some releases names a crate the registry has withdrawn.
    cargo install -q wasm-bindgen-cli --version "=$version" --locked \
        || cargo install -q wasm-bindgen-cli --version "=$version"
fi

cargo build -q -p lagrange-web --target wasm32-unknown-unknown --profile web
rm -rf "$out"
mkdir -p "$out"
wasm-bindgen --target web --no-typescript --out-dir "$out/pkg" \
    target/wasm32-unknown-unknown/web/lagrange_web.wasm
cp web/index.html web/playground.css web/playground.js web/worker.js "$out/"
python3 - "$out/examples.json" <<'PY'
import json, pathlib, re, sys
root = pathlib.Path("examples")
files = {p.relative_to(root).as_posix(): p.read_text() for p in sorted(root.rglob("*.toml"))}
models = [{"path": path} for path, text in files.items() if re.search(r"^coordinates", text, re.M)]
pathlib.Path(sys.argv[1]).write_text(json.dumps({"models": models, "files": files}))
PY
echo "$out"

//! The playground's JS glue is written by `crates/web/bindgen` (a workspace of
//! its own, which `web/build.sh` runs) with `wasm-bindgen-cli-support`; the
//! module it reads was built with the `wasm-bindgen` crate. Both come from one
//! release or the generator refuses the module: the two pins must be equal.

/// The version after `NAME = "` on the manifest line that starts with `NAME = `.
fn pin(manifest: &str, name: &str) -> String {
    let prefix = format!("{name} = ");
    let line = manifest
        .lines()
        .find(|line| line.starts_with(&prefix))
        .unwrap_or_else(|| panic!("no line {prefix}... in the manifest"));
    let version = line.split('"').nth(1).expect("a quoted version");
    assert!(version.starts_with('='), "{name} is pinned exactly: {line}");
    version.to_string()
}

#[test]
fn generator_and_runtime_are_the_same_release() {
    let runtime = pin(include_str!("../Cargo.toml"), "wasm-bindgen");
    let generator = pin(include_str!("../bindgen/Cargo.toml"), "wasm-bindgen-cli-support");
    assert_eq!(runtime, generator, "crates/web's wasm-bindgen and crates/web/bindgen's cli-support");
}

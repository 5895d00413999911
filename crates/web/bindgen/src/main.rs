//! The host tool that writes the playground's JS glue: `web/build.sh` runs
//!
//!     lagrange-web-bindgen INPUT.wasm OUT_DIR
//!
//! on the `wasm32-unknown-unknown` build of `crates/web`, and gets what
//! `wasm-bindgen --target web --no-typescript --out-dir OUT_DIR INPUT.wasm`
//! writes (the module and `lagrange_web.js`), from wasm-bindgen's generator
//! linked as a library (`wasm-bindgen-cli-support`, pinned to the version of
//! the `wasm-bindgen` crate). Installing `wasm-bindgen-cli` from source
//! would build its test runner too and cost CI many minutes.

use std::process::ExitCode;
use wasm_bindgen_cli_support::Bindgen;

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let [input, out_dir] = args.as_slice() else {
        eprintln!("usage: lagrange-web-bindgen INPUT.wasm OUT_DIR");
        return ExitCode::from(2);
    };
    // The glue for the browser's ES modules (`--target web`), without TypeScript
    // declarations, with the CLI's other defaults: notably the default path of the
    // module beside the glue (`omit_default_module_path(false)`, which the CLI sets
    // and the library's `Bindgen::new` does not).
    let generated = Bindgen::new()
        .input_path(input)
        .web(true)
        .and_then(|bindgen| bindgen.typescript(false).omit_default_module_path(false).generate(out_dir));
    match generated {
        Ok(()) => ExitCode::SUCCESS,
        Err(error) => {
            eprintln!("lagrange-web-bindgen: {input}: {error:#}");
            ExitCode::from(1)
        }
    }
}

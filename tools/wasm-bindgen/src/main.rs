//! `raypipe-wasm-bindgen INPUT.wasm OUT_DIR`: the JavaScript glue and the processed module of a
//! `wasm32-unknown-unknown` build, as `wasm-bindgen --target web --no-typescript` writes them.

use anyhow::{Context, bail};
use std::path::PathBuf;

fn main() -> anyhow::Result<()> {
    let args: Vec<PathBuf> = std::env::args_os().skip(1).map(PathBuf::from).collect();
    let [input, out_dir] = &args[..] else {
        bail!("usage: raypipe-wasm-bindgen INPUT.wasm OUT_DIR");
    };
    wasm_bindgen_cli_support::Bindgen::new()
        .input_path(input)
        .web(true)?
        .typescript(false)
        // As the CLI does for --target web: init() with no argument fetches the module beside the glue.
        .omit_default_module_path(false)
        .generate(out_dir)
        .with_context(|| format!("wasm-bindgen on {}", input.display()))
}

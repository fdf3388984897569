//! Compiles the segment's C shim (`firmware-segment/c-shim/src/segment.c`) for the host, so
//! `tests/cross/c_shim_bit_exact.rs` can call it next to the Rust crates.

use std::path::PathBuf;

fn main() {
    let manifest = PathBuf::from(std::env::var_os("CARGO_MANIFEST_DIR").unwrap_or_default());
    let shim = manifest.join("../firmware-segment/c-shim");
    let source = shim.join("src/segment.c");
    let include = shim.join("include");
    println!("cargo::rerun-if-changed={}", source.display());
    println!(
        "cargo::rerun-if-changed={}",
        include.join("segment.h").display()
    );
    cc::Build::new()
        .file(&source)
        .include(&include)
        .std("c99")
        .warnings(true)
        .extra_warnings(true)
        .warnings_into_errors(true)
        .compile("segment_shim");
}

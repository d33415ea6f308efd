//! Puts the board's memory layout in OUT_DIR as `memory.x` (cortex-m-rt's `link.x` includes it):
//! `memory-qemu.x` for `board-qemu`, the repository's `memory.x` (STM32F446RE) for `board-stm32f4`.
//! PC builds (tests) need neither.

use std::{env, fs, path::PathBuf};

fn main() {
    println!("cargo:rerun-if-changed=build.rs");
    println!("cargo:rerun-if-changed=memory-qemu.x");
    println!("cargo:rerun-if-changed=../memory.x");
    let target = env::var("TARGET").unwrap_or_default();
    if !target.starts_with("thumb") {
        return;
    }
    let qemu = env::var_os("CARGO_FEATURE_BOARD_QEMU").is_some();
    let stm32 = env::var_os("CARGO_FEATURE_BOARD_STM32F4").is_some();
    let source = match (qemu, stm32) {
        (true, true) => panic!(
            "features board-qemu and board-stm32f4 are exclusive: build QEMU with \
             --no-default-features --features board-qemu"
        ),
        (true, false) => "memory-qemu.x",
        (false, true) => "../memory.x",
        (false, false) => return, // the library alone
    };
    let out = PathBuf::from(env::var_os("OUT_DIR").unwrap());
    fs::copy(source, out.join("memory.x")).expect("copy memory layout");
    println!("cargo:rustc-link-search={}", out.display());
}

//! Puts the board's memory layout in OUT_DIR as `memory.x` (cortex-m-rt's `link.x` includes it):
//! `memory-qemu.x` for `board-qemu`, the repository's `memory.x` (STM32F446RE) for `board-stm32f4`,
//! `memory-f405.x` for `board-f405`; for the QEMU board also an empty `device.x` (its interrupt
//! table is `board::qemu::__INTERRUPTS`). PC builds (tests) need none.

use std::{env, fs, path::PathBuf};

fn main() {
    println!("cargo:rerun-if-changed=build.rs");
    println!("cargo:rerun-if-changed=memory-qemu.x");
    println!("cargo:rerun-if-changed=../memory.x");
    println!("cargo:rerun-if-changed=memory-f405.x");
    let target = env::var("TARGET").unwrap_or_default();
    if !target.starts_with("thumb") {
        return;
    }
    let boards: Vec<(&str, &str)> = [
        ("BOARD_QEMU", "memory-qemu.x"),
        ("BOARD_STM32F4", "../memory.x"),
        ("BOARD_F405", "memory-f405.x"),
    ]
    .into_iter()
    .filter(|(feature, _)| env::var_os(format!("CARGO_FEATURE_{feature}")).is_some())
    .collect();
    let source = match boards.as_slice() {
        [] => return, // the library alone
        [(_, layout)] => *layout,
        _ => panic!(
            "the board features are exclusive: build QEMU with --no-default-features --features \
             board-qemu, the F405 with --no-default-features --features board-f405"
        ),
    };
    let out = PathBuf::from(env::var_os("OUT_DIR").unwrap());
    fs::copy(source, out.join("memory.x")).expect("copy memory layout");
    if env::var_os("CARGO_FEATURE_BOARD_QEMU").is_some() {
        // cortex-m-rt's `device` feature makes link.x include a `device.x` (a PAC's, on the STM32
        // boards): the QEMU board's interrupt table names only `DefaultHandler`, so it is empty.
        fs::write(
            out.join("device.x"),
            "/* mps2-an386: no device interrupt handlers */\n",
        )
        .expect("write device.x");
    }
    println!("cargo:rustc-link-search={}", out.display());
}

//! The exported C package cross-compiled for the Cortex-M4F (`arm-none-eabi-gcc`, hard float) and run
//! in QEMU on the firmware's board (`mps2-an386`): the same `main.c` and the same vectors as the x86
//! run, bit for bit the Rust `f32` path. The program's input is compiled into it (read through
//! newlib's `fmemopen` as `stdin`); its output and exit status come back over semihosting
//! (`--specs=rdimon.specs`).

use super::*;
use std::io::Read as _;
use std::time::{Duration, Instant};

/// The Cortex-M4F flags of the brief's build: single-precision FPU, hard-float ABI, strict warnings,
/// and no fused multiply-add (the Rust path rounds every product).
const ARM_FLAGS: &[&str] = &[
    "-mcpu=cortex-m4",
    "-mfpu=fpv4-sp-d16",
    "-mfloat-abi=hard",
    "-mthumb",
    "-O2",
    "-Wall",
    "-Wextra",
    "-Werror",
    "-std=c99",
    "-ffp-contract=off",
];

/// How long QEMU may run before it is killed and the test fails (the run takes well under a second).
const QEMU_TIMEOUT: Duration = Duration::from_secs(20);

/// The bare-metal frame around [`PACKAGE_MAIN_C`] (included as `main.c`, its `main` renamed): a
/// vector table at address 0 (QEMU's M-profile reset loads SP and PC from it), a reset handler
/// that enables the FPU before newlib's `_start` runs, and a `main` that makes the compiled-in input
/// the program's `stdin`. `input.h` defines `acal_input`.
const CROSS_MAIN_C: &str = r#"
#define _POSIX_C_SOURCE 200809L
#include <stdint.h>
#include <stdio.h>
#include "input.h"
#define main acal_vectors_main
#include "main.c"
#undef main

extern void _start(void);

/* Reset: grant CP10/CP11 (the FPU) full access in CPACR before any float instruction, then newlib's
   start-up (semihosting heap/stack query, .bss, constructors, main, exit). */
static void acal_reset(void) {
    *(volatile uint32_t *)0xE000ED88u |= 0xFu << 20;
    __asm__ volatile("dsb\n\tisb");
    _start();
}

/* Any fault stops here; QEMU's timeout then fails the test. */
static void acal_fault(void) {
    for (;;) {
    }
}

/* Initial SP: the top of mps2-an386's 4 MiB SSRAM1 at 0x0 (newlib moves it after SYS_HEAPINFO). */
__attribute__((section(".acal_vectors"), used)) static void (*const acal_vectors[16])(void) = {
    (void (*)(void))0x00400000u, acal_reset, acal_fault, acal_fault, acal_fault, acal_fault, acal_fault,
};

int main(void) {
    stdin = fmemopen((void *)acal_input, sizeof acal_input - 1, "r");
    if (stdin == NULL) return 3;
    return acal_vectors_main();
}
"#;

/// `input.h`: `text` as one C string, a literal per line.
fn input_header(text: &str) -> String {
    let mut h = String::from("static const char acal_input[] =\n");
    for line in text.lines() {
        h += &format!("    \"{line}\\n\"\n");
    }
    h + "    \"\";\n"
}

/// Fails (never skips) when `tool` is absent, naming the Debian packages that provide it.
fn require_tool(tool: &str, packages: &str) {
    let found = Command::new(tool)
        .arg("--version")
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .status()
        .is_ok_and(|s| s.success());
    assert!(
        found,
        "{tool} not found: install it with `apt-get install --no-install-recommends {packages}` \
         (scripts/test-all.sh does)"
    );
}

/// Cross-compiles the package in `dir` (with `main.c`) and `input` into `dir/prog.elf`.
fn cross_compile(dir: &Path, input: &str, flags: &[&str]) {
    std::fs::write(dir.join("input.h"), input_header(input)).unwrap();
    std::fs::write(dir.join("cross_main.c"), CROSS_MAIN_C).unwrap();
    let out = Command::new("arm-none-eabi-gcc")
        .current_dir(dir)
        .args(flags)
        .args([
            "--specs=rdimon.specs",
            "-Wl,--section-start=.acal_vectors=0",
            "cross_main.c",
            "acal_blob.c",
            "acal_device.c",
            "-lm",
            "-o",
            "prog.elf",
        ])
        .output()
        .expect("arm-none-eabi-gcc runs");
    assert!(
        out.status.success(),
        "arm-none-eabi-gcc {flags:?} (rdimon.specs comes with libnewlib-arm-none-eabi): {}",
        String::from_utf8_lossy(&out.stderr)
    );
}

/// Runs `elf` on the firmware's QEMU board (`firmware/scripts/qemu-board.sh`, the one definition of
/// its arguments) and returns what it printed over semihosting; fails if it exits non-zero or is
/// still running after [`QEMU_TIMEOUT`] (then it is killed).
fn run_in_qemu(elf: &Path) -> String {
    let board = Path::new(env!("CARGO_MANIFEST_DIR")).join("../firmware/scripts/qemu-board.sh");
    let mut child = Command::new("bash")
        .args([
            "-c",
            r#"source "$1" && shift && exec "${QEMU_BOARD[@]}" "$@""#,
            "qemu-board",
        ])
        .arg(&board)
        .args(["-serial", "null", "-kernel"])
        .arg(elf)
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("bash starts qemu-system-arm");
    // Drain both pipes while QEMU runs so that it never blocks on a full one.
    let drain = |mut stream: Box<dyn std::io::Read + Send>| {
        std::thread::spawn(move || {
            let mut text = String::new();
            stream.read_to_string(&mut text).map(|_| text)
        })
    };
    let stdout = drain(Box::new(child.stdout.take().unwrap()));
    let stderr = drain(Box::new(child.stderr.take().unwrap()));
    let start = Instant::now();
    let status = loop {
        if let Some(status) = child.try_wait().unwrap() {
            break status;
        }
        if start.elapsed() > QEMU_TIMEOUT {
            child.kill().unwrap();
            child.wait().unwrap();
            panic!("QEMU still running after {QEMU_TIMEOUT:?}: killed");
        }
        std::thread::sleep(Duration::from_millis(20));
    };
    let stdout = stdout.join().unwrap().unwrap();
    let stderr = stderr.join().unwrap().unwrap();
    assert!(status.success(), "QEMU: {status}: {stderr}");
    stdout
}

/// The package `host export --format c --out DIR` writes, built for the Cortex-M4F with
/// `arm-none-eabi-gcc` and run in QEMU `mps2-an386` on the x86 test's vectors: bit for bit the Rust
/// device's and host apply's f32 path.
#[test]
fn c_package_cross_compiled_for_the_cortex_m4f_runs_bit_exact_in_qemu() {
    require_tool(
        "arm-none-eabi-gcc",
        "gcc-arm-none-eabi libnewlib-arm-none-eabi",
    );
    require_tool("qemu-system-arm", "qemu-system-arm");
    for (cal, vectors) in [
        (firmware::paper_unit::calibration(), "comp"),
        (imperfect_unit(), "gyro-temp"),
    ] {
        let dir = tempfile::tempdir().unwrap();
        let out = exported_package(dir.path(), &cal);
        let (stdin, want) = package_vectors(&cal, vectors);
        cross_compile(&out, &stdin, ARM_FLAGS);
        let got = run_in_qemu(&out.join("prog.elf"));
        assert_package_output(&got, &want, &format!("{vectors} cortex-m4f in QEMU"));
    }
}

//! Runs the QEMU firmware (`mps2-an386`) with its UART on a pty, for host-in-the-loop tests.

use std::io::{BufRead, BufReader};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::sync::mpsc;
use std::time::Duration;

/// The repository root.
pub fn repo_root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

/// Builds the QEMU firmware (release) and returns the ELF path. Runs from the repository root so that
/// the root `.cargo/config.toml` (linker scripts) applies.
pub fn build_firmware() -> Result<PathBuf, String> {
    let root = repo_root();
    let status = Command::new(env!("CARGO"))
        .current_dir(&root)
        .args([
            "build",
            "--manifest-path",
            "firmware/Cargo.toml",
            "--release",
            "--no-default-features",
            "--features",
            "board-qemu",
            "--bin",
            "qemu",
            "--target",
            "thumbv7em-none-eabihf",
        ])
        .status()
        .map_err(|e| format!("cannot run cargo: {e}"))?;
    if !status.success() {
        return Err(
            "building the QEMU firmware failed (is the thumbv7em-none-eabihf target installed?)"
                .into(),
        );
    }
    Ok(firmware_target_dir(&root)?.join("thumbv7em-none-eabihf/release/qemu"))
}

/// The firmware workspace's build directory as cargo places it (`CARGO_TARGET_DIR` or a config's
/// `build.target-dir` when set, else `firmware/target`), from `cargo metadata`.
fn firmware_target_dir(root: &Path) -> Result<PathBuf, String> {
    let out = Command::new(env!("CARGO"))
        .current_dir(root)
        .args([
            "metadata",
            "--format-version",
            "1",
            "--no-deps",
            "--manifest-path",
            "firmware/Cargo.toml",
        ])
        .output()
        .map_err(|e| format!("cannot run cargo metadata: {e}"))?;
    let doc: serde_json::Value = serde_json::from_slice(&out.stdout)
        .map_err(|e| format!("cargo metadata gave no JSON document ({e})"))?;
    doc["target_directory"]
        .as_str()
        .map(PathBuf::from)
        .ok_or_else(|| "cargo metadata names no target_directory".into())
}

/// A running emulated board.
pub struct Qemu {
    child: Child,
    /// The pty its UART0 is connected to.
    pub pty: String,
}

impl Qemu {
    /// Starts `elf` on `mps2-an386` with UART0 on a new pty and waits for QEMU to name the pty. The
    /// board's arguments come from `firmware/scripts/qemu-board.sh`, which the firmware's scripts
    /// source too: one definition of the emulated board.
    pub fn start(elf: &Path) -> Result<Qemu, String> {
        let missing = |e: std::io::Error| {
            format!("cannot start qemu-system-arm ({e}): install it with `apt-get install qemu-system-arm`")
        };
        Command::new("qemu-system-arm")
            .arg("--version")
            .stdout(Stdio::null())
            .status()
            .map_err(missing)?;
        let board = repo_root().join("firmware/scripts/qemu-board.sh");
        let mut child = Command::new("bash")
            .args([
                "-c",
                r#"source "$1" && shift && exec "${QEMU_BOARD[@]}" "$@""#,
                "qemu-board",
            ])
            .arg(&board)
            .args(["-serial", "pty", "-kernel"])
            .arg(elf)
            .stdin(Stdio::null())
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .map_err(missing)?;
        // QEMU names the pty on stdout ("char device redirected to /dev/pts/N (label serial0)"); keep
        // draining both streams so that it never blocks on a full pipe.
        let (tx, rx) = mpsc::channel();
        let stdout = child.stdout.take().ok_or("no stdout from QEMU")?;
        let stderr = child.stderr.take().ok_or("no stderr from QEMU")?;
        let readers: [Box<dyn std::io::Read + Send>; 2] = [Box::new(stdout), Box::new(stderr)];
        for stream in readers {
            let tx = tx.clone();
            std::thread::spawn(move || {
                for line in BufReader::new(stream).lines().map_while(Result::ok) {
                    if let Some(pos) = line.find("/dev/pts/") {
                        let pty = line[pos..]
                            .split_whitespace()
                            .next()
                            .unwrap_or_default()
                            .to_string();
                        let _ = tx.send(pty);
                    }
                }
            });
        }
        match rx.recv_timeout(Duration::from_secs(20)) {
            Ok(pty) => Ok(Qemu { child, pty }),
            Err(_) => {
                let _ = child.kill();
                Err("QEMU did not report its serial pty within 20 s".into())
            }
        }
    }

    /// True while QEMU runs.
    pub fn running(&mut self) -> bool {
        matches!(self.child.try_wait(), Ok(None))
    }
}

impl Drop for Qemu {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

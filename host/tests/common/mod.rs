//! Running the built `host` binary, shared by the integration tests.

use std::path::Path;
use std::process::Command;

/// Runs `host ARGS` (in `cwd` when given): success, stdout, stderr.
pub fn host_in(cwd: Option<&Path>, args: &[&str]) -> (bool, String, String) {
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_host"));
    cmd.args(args);
    if let Some(d) = cwd {
        cmd.current_dir(d);
    }
    let out = cmd.output().expect("the host binary runs");
    (
        out.status.success(),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

/// Runs `host ARGS` in the current directory.
#[allow(dead_code)] // not every test file uses both
pub fn host(args: &[&str]) -> (bool, String, String) {
    host_in(None, args)
}

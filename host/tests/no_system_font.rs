//! The figures need no font of the machine's: with the system's font directory hidden (an empty
//! file system mounted over it in a private mount namespace), `host noise` still writes its PNG, and
//! the same bytes as with the fonts visible.

use std::path::Path;
use std::process::Command;

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// Can this machine hide a directory from one process (user and mount namespaces)?
fn can_hide_directories() -> bool {
    Command::new("unshare")
        .args(["-r", "-m", "true"])
        .output()
        .is_ok_and(|o| o.status.success())
}

#[test]
fn a_png_is_written_with_the_system_fonts_hidden() {
    const FONTS: &str = "/usr/share/fonts";
    if !Path::new(FONTS).is_dir() || !can_hide_directories() {
        // Nothing to hide, or no way to: the in-process test
        // `report::plot::tests::png_is_drawn_with_the_embedded_font_and_no_font_lookup` still runs.
        eprintln!("skipped: {FONTS} absent or unshare unavailable");
        return;
    }
    let host = env!("CARGO_BIN_EXE_host");
    let dir = tempfile::tempdir().unwrap();
    let session = dir.path().join("s");
    let sim = Command::new(host)
        .args(["-q", "simulate", "--out", s(&session), "--plan", "short"])
        .output()
        .unwrap();
    assert!(sim.status.success());
    let run = |out: &Path, hide: bool| {
        let script = if hide {
            format!(
                "mount -t tmpfs none {FONTS} && test -z \"$(ls -A {FONTS})\" && exec \"$0\" \"$@\""
            )
        } else {
            "exec \"$0\" \"$@\"".to_string()
        };
        let o = Command::new("unshare")
            .args(["-r", "-m", "sh", "-c", &script, host])
            .args(["-q", "noise", "--input", s(&session), "--out", s(out)])
            .output()
            .unwrap();
        let stderr = String::from_utf8_lossy(&o.stderr).into_owned();
        assert!(o.status.success(), "{stderr}");
        assert!(!stderr.contains("font"), "{stderr}");
        std::fs::read(out.join("allan.png")).expect("allan.png written")
    };
    let hidden = run(&dir.path().join("hidden"), true);
    let visible = run(&dir.path().join("visible"), false);
    assert!(hidden.starts_with(b"\x89PNG"));
    assert_eq!(
        hidden, visible,
        "the same figure with and without system fonts"
    );
}

//! The README's layout table and each module's own map name every source file of the PC crates'
//! module folders (the src of each PC crate but `shared`), so that a reader who looks a piece up by its name
//! finds it.

use std::path::Path;

/// The `.rs` files of a module folder that are not tests and not `mod.rs`, without the extension.
fn modules(dir: &Path) -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .filter_map(|e| {
            let name = e.unwrap().file_name().into_string().unwrap();
            let stem = name.strip_suffix(".rs")?.to_string();
            (stem != "mod" && !stem.contains("tests")).then_some(stem)
        })
        .collect();
    names.sort();
    names
}

#[test]
fn readme_and_module_maps_name_every_file() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let readme = std::fs::read_to_string(root.join("../README.md")).unwrap();
    let layout = &readme[readme.find("## Layout").unwrap()..];
    let mut missing = Vec::new();
    for krate in ["host", "device", "app", "outputs", "estimator", "recording"] {
        missing.extend(unnamed(&root.join("..").join(krate), krate, layout));
    }
    assert!(missing.is_empty(), "{}", missing.join("\n"));
}

/// What `krate`'s module maps and the README's rows for its folders do not name: the crate root's
/// map (`lib.rs`) names each top-level module, and each folder's `mod.rs` the files in it.
fn unnamed(crate_dir: &Path, krate: &str, layout: &str) -> Vec<String> {
    let mut missing = Vec::new();
    let lib = std::fs::read_to_string(crate_dir.join("src/lib.rs")).unwrap();
    let lib_doc: String = lib.lines().take_while(|l| l.starts_with("//!")).collect();
    let root_row = layout
        .lines()
        .find(|l| l.starts_with(&format!("| `{krate}/src/` |")));
    for m in modules(&crate_dir.join("src")) {
        if ["lib", "main"].contains(&m.as_str()) {
            continue;
        }
        if !lib_doc.contains(&format!("`{m}`")) {
            missing.push(format!("{krate}/src/lib.rs's module map does not name {m}"));
        }
        if root_row.is_some_and(|row| !row.contains(&format!("`{m}.rs`"))) {
            missing.push(format!(
                "README's layout row for {krate}/src/ does not name {m}.rs"
            ));
        }
    }
    for entry in std::fs::read_dir(crate_dir.join("src")).unwrap() {
        let dir = entry.unwrap().path();
        let Ok(map) = std::fs::read_to_string(dir.join("mod.rs")) else {
            continue;
        };
        let folder = dir.file_name().unwrap().to_str().unwrap().to_string();
        let doc: String = map
            .lines()
            .take_while(|l| l.starts_with("//!"))
            .collect::<Vec<_>>()
            .join("\n");
        let row = layout
            .lines()
            .find(|l| l.starts_with(&format!("| `{krate}/src/{folder}/`")));
        for m in modules(&dir) {
            if !doc.contains(&format!("`{m}`")) && !doc.contains(&format!("`mod@{m}`")) {
                missing.push(format!(
                    "{krate}/src/{folder}/mod.rs's module map does not name {m}"
                ));
            }
            // A folder the README describes in a shared row (`noise/`) is named as a whole there.
            if let Some(row) = row {
                if !row.contains(&format!("`{m}.rs`")) {
                    missing.push(format!(
                        "README's layout row for {krate}/src/{folder}/ does not name {m}.rs"
                    ));
                }
            }
        }
    }
    missing
}

//! The shape check: no non-test function over 100 lines and no file over 700 lines of non-test code,
//! in the crates' sources (`shared/src`, `recording/src`, `estimator/src`, `outputs/src`, `app/src`, `device/src`, `host/src`, `host/examples`, `firmware/src`, `python/src`), unless a
//! comment right above the function (or at the top of the file) says why it reads better whole:
//!
//! ```text
//! // shape: reads better whole because <the reason>
//! ```
//!
//! It is measured with a Rust parser (`syn`), not by counting braces, so braces inside strings and
//! format strings are not code. Test code is left out: items and modules under `#[cfg(test)]` (or a
//! `cfg` that requires `test`), `#[test]` functions, and whole files that only a test module declares
//! (`#[cfg(test)] mod tests;` makes `tests.rs` test code) or that only test code `include!`s. A file
//! is test code only if every declaration of it is test code. The `e2e` crate (`tests/`) and the
//! crates' `tests/` folders are test code as a whole and are not read.
//!
//! A function's lines run from its `fn` line to its closing brace (its doc comment and attributes
//! are not counted); a file's lines are all its lines less those of its test items. The check
//! prints, straight to the terminal (not captured), every function over 80 lines and every file over
//! 600, with the reason where one is given.

use proc_macro2::Span;
use std::collections::{BTreeMap, BTreeSet};
use std::io::Write;
use std::path::{Path, PathBuf};
use syn::spanned::Spanned;
use syn::visit::Visit;

/// What a comment must say, right above a function or at the top of a file, to allow it over the
/// limit; the reason follows on the same line.
const MARKER: &str = "shape: reads better whole because";
/// A non-test function over this many lines fails without a reason.
const FUNCTION_LIMIT_LINES: usize = 100;
/// A file with more non-test lines than this fails without a reason.
const FILE_LIMIT_LINES: usize = 700;
/// Functions over this many lines are printed.
const FUNCTION_REPORT_LINES: usize = 80;
/// Files with more non-test lines than this are printed.
const FILE_REPORT_LINES: usize = 600;

/// The source folders checked, relative to the repository root.
const ROOTS: [&str; 10] = [
    "shared/src",
    "recording/src",
    "estimator/src",
    "outputs/src",
    "app/src",
    "device/src",
    "host/src",
    "host/examples",
    "firmware/src",
    "python/src",
];

/// One function or file over its report threshold.
#[derive(Debug)]
struct Finding {
    /// `path:line fn name` or `path`.
    place: String,
    /// Lines counted.
    lines: usize,
    /// The limit it is measured against.
    limit: usize,
    /// The reason after [`MARKER`], when one is given.
    reason: Option<String>,
}

impl Finding {
    /// Over its limit without a reason.
    fn fails(&self) -> bool {
        self.lines > self.limit && self.reason.is_none()
    }
}

impl std::fmt::Display for Finding {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{:>5} lines  {}", self.lines, self.place)?;
        match (&self.reason, self.fails()) {
            (Some(r), _) => write!(f, "  (allowed: reads better whole because {r})"),
            (None, true) => write!(f, "  OVER {} lines and no `// {MARKER} …`", self.limit),
            (None, false) => Ok(()),
        }
    }
}

/// A `mod name;` or `include!("…")` found in a file: the file it names (`name.rs` or `name/mod.rs`:
/// the first that exists) and whether the declaration is test code.
struct Declaration {
    candidates: Vec<PathBuf>,
    test: bool,
}

/// What one parse of a file yields.
#[derive(Default)]
struct FileFacts {
    /// 1-based line ranges (inclusive) of test items.
    test_lines: Vec<(usize, usize)>,
    /// Non-test functions: name, `fn` line, lines.
    functions: Vec<(String, usize, usize)>,
    /// The files this one declares or includes.
    declarations: Vec<Declaration>,
}

/// Walks one file's syntax tree, knowing whether the code it is in is test code.
struct Walker {
    /// The file's directory, against which `include!` and `#[path]` resolve.
    dir: PathBuf,
    /// Where `mod name;` files are looked for at the top level of this file.
    mod_dir: PathBuf,
    /// Inline modules around the current item (`mod a { mod b; }` looks in `a/`).
    inline: Vec<String>,
    in_test: bool,
    facts: FileFacts,
}

fn line(span: Span) -> usize {
    span.start().line
}

fn end_line(span: Span) -> usize {
    span.end().line
}

/// True when a `cfg` predicate can only hold in a test build.
fn requires_test(meta: &syn::Meta) -> bool {
    match meta {
        syn::Meta::Path(p) => p.is_ident("test"),
        syn::Meta::List(list) => {
            let Ok(args) = list.parse_args_with(
                syn::punctuated::Punctuated::<syn::Meta, syn::Token![,]>::parse_terminated,
            ) else {
                return false;
            };
            if list.path.is_ident("all") {
                args.iter().any(requires_test)
            } else if list.path.is_ident("any") {
                !args.is_empty() && args.iter().all(requires_test)
            } else {
                false
            }
        }
        syn::Meta::NameValue(_) => false,
    }
}

/// `#[cfg(test)]` (or a `cfg` requiring `test`) or `#[test]` (any `…::test`).
fn is_test(attrs: &[syn::Attribute]) -> bool {
    attrs.iter().any(|a| {
        let last = a.path().segments.last().map(|s| s.ident.to_string());
        if last.as_deref() == Some("test") {
            return true;
        }
        a.path().is_ident("cfg") && a.parse_args::<syn::Meta>().is_ok_and(|m| requires_test(&m))
    })
}

fn item_attrs(item: &syn::Item) -> &[syn::Attribute] {
    use syn::Item::*;
    match item {
        Const(i) => &i.attrs,
        Enum(i) => &i.attrs,
        ExternCrate(i) => &i.attrs,
        Fn(i) => &i.attrs,
        ForeignMod(i) => &i.attrs,
        Impl(i) => &i.attrs,
        Macro(i) => &i.attrs,
        Mod(i) => &i.attrs,
        Static(i) => &i.attrs,
        Struct(i) => &i.attrs,
        Trait(i) => &i.attrs,
        TraitAlias(i) => &i.attrs,
        Type(i) => &i.attrs,
        Union(i) => &i.attrs,
        Use(i) => &i.attrs,
        _ => &[],
    }
}

fn impl_item_attrs(item: &syn::ImplItem) -> &[syn::Attribute] {
    match item {
        syn::ImplItem::Const(i) => &i.attrs,
        syn::ImplItem::Fn(i) => &i.attrs,
        syn::ImplItem::Type(i) => &i.attrs,
        syn::ImplItem::Macro(i) => &i.attrs,
        _ => &[],
    }
}

/// The value of `#[path = "…"]`, if any.
fn path_attr(attrs: &[syn::Attribute]) -> Option<String> {
    attrs.iter().find_map(|a| match &a.meta {
        syn::Meta::NameValue(nv) if nv.path.is_ident("path") => match &nv.value {
            syn::Expr::Lit(syn::ExprLit {
                lit: syn::Lit::Str(s),
                ..
            }) => Some(s.value()),
            _ => None,
        },
        _ => None,
    })
}

impl Walker {
    /// Runs `f` with the test flag set when `test`, marking `span`'s lines as test code.
    fn scoped(&mut self, test: bool, span: Span, f: impl FnOnce(&mut Self)) {
        let was = self.in_test;
        if test && !was {
            self.facts.test_lines.push((line(span), end_line(span)));
        }
        self.in_test = was || test;
        f(self);
        self.in_test = was;
    }

    /// Records a non-test function whose signature is `sig` and whose body ends at `end`.
    fn function(&mut self, name: String, sig: Span, end: Span) {
        if !self.in_test {
            let (from, to) = (line(sig), end_line(end));
            self.facts.functions.push((name, from, to + 1 - from));
        }
    }

    /// The directory `mod name;` resolves in, here.
    fn current_mod_dir(&self) -> PathBuf {
        self.inline
            .iter()
            .fold(self.mod_dir.clone(), |d, m| d.join(m))
    }
}

impl<'ast> Visit<'ast> for Walker {
    fn visit_item(&mut self, item: &'ast syn::Item) {
        let test = is_test(item_attrs(item));
        self.scoped(test, item.span(), |w| syn::visit::visit_item(w, item));
    }

    fn visit_impl_item(&mut self, item: &'ast syn::ImplItem) {
        let test = is_test(impl_item_attrs(item));
        self.scoped(test, item.span(), |w| syn::visit::visit_impl_item(w, item));
    }

    fn visit_item_mod(&mut self, m: &'ast syn::ItemMod) {
        let name = m.ident.to_string();
        match &m.content {
            None => {
                let base = self.current_mod_dir();
                let candidates = match path_attr(&m.attrs) {
                    Some(p) if self.inline.is_empty() => vec![self.dir.join(p)],
                    Some(p) => vec![base.join(p)],
                    None => vec![
                        base.join(format!("{name}.rs")),
                        base.join(&name).join("mod.rs"),
                    ],
                };
                self.facts.declarations.push(Declaration {
                    candidates,
                    test: self.in_test,
                });
            }
            Some(_) => {
                self.inline.push(path_attr(&m.attrs).unwrap_or(name));
                syn::visit::visit_item_mod(self, m);
                self.inline.pop();
            }
        }
    }

    fn visit_item_fn(&mut self, f: &'ast syn::ItemFn) {
        self.function(
            f.sig.ident.to_string(),
            f.sig.span(),
            f.block.brace_token.span.close(),
        );
        syn::visit::visit_item_fn(self, f);
    }

    fn visit_impl_item_fn(&mut self, f: &'ast syn::ImplItemFn) {
        self.function(
            f.sig.ident.to_string(),
            f.sig.span(),
            f.block.brace_token.span.close(),
        );
        syn::visit::visit_impl_item_fn(self, f);
    }

    fn visit_trait_item_fn(&mut self, f: &'ast syn::TraitItemFn) {
        if let Some(block) = &f.default {
            self.function(
                f.sig.ident.to_string(),
                f.sig.span(),
                block.brace_token.span.close(),
            );
        }
        syn::visit::visit_trait_item_fn(self, f);
    }

    fn visit_macro(&mut self, m: &'ast syn::Macro) {
        if m.path.is_ident("include") {
            if let Ok(lit) = m.parse_body::<syn::LitStr>() {
                self.facts.declarations.push(Declaration {
                    candidates: vec![self.dir.join(lit.value())],
                    test: self.in_test,
                });
            }
        }
        syn::visit::visit_macro(self, m);
    }
}

/// The reason given by a [`MARKER`] comment in `source_lines` (1-based, inclusive `from..=to`): the
/// rest of its line and of the plain `//` comment lines that continue it.
fn marker_in(source_lines: &[&str], from: usize, to: usize) -> Option<String> {
    let plain = |n: usize| {
        let text = source_lines.get(n - 1)?.trim_start();
        let rest = text.strip_prefix("//")?;
        (!rest.starts_with('/') && !rest.starts_with('!')).then_some(rest)
    };
    (from.max(1)..=to.min(source_lines.len())).find_map(|n| {
        let first = plain(n)?.split_once(MARKER)?.1.trim();
        if first.is_empty() {
            return None;
        }
        let more = (n + 1..).map_while(plain).map(str::trim);
        let words: Vec<&str> = std::iter::once(first).chain(more).collect();
        Some(words.join(" "))
    })
}

/// The comment block right above line `first` (the item's first attribute or doc line), with the
/// item's own attribute lines down to its `fn` line: where a function's [`MARKER`] may stand.
fn marker_above(source_lines: &[&str], first: usize, fn_line: usize) -> Option<String> {
    let mut top = first;
    while top > 1 && source_lines[top - 2].trim_start().starts_with("//") {
        top -= 1;
    }
    marker_in(source_lines, top, fn_line)
}

/// Canonical form of a path for matching declarations to files: no `.` or `..` components.
fn normal(p: &Path) -> PathBuf {
    let mut out = PathBuf::new();
    for c in p.components() {
        match c {
            std::path::Component::CurDir => {}
            std::path::Component::ParentDir => {
                out.pop();
            }
            other => out.push(other),
        }
    }
    out
}

/// True for a file whose `mod name;` files live beside it (`lib.rs`, `main.rs`, `mod.rs`, a binary
/// in `bin/`, an example), not in a folder named after it.
fn is_mod_rs_like(path: &Path) -> bool {
    let name = path.file_name().and_then(|n| n.to_str()).unwrap_or("");
    let parent = path
        .parent()
        .and_then(|p| p.file_name())
        .and_then(|n| n.to_str())
        .unwrap_or("");
    matches!(name, "lib.rs" | "main.rs" | "mod.rs") || matches!(parent, "bin" | "examples")
}

/// Parses `source` of `path`.
fn parse(path: &Path, source: &str) -> Result<syn::File, String> {
    syn::parse_file(source)
        .map_err(|e| format!("{}:{}: does not parse: {e}", path.display(), line(e.span())))
}

/// Walks the parsed `file` of `path`, as test code when `test`.
fn walk(path: &Path, file: &syn::File, test: bool) -> FileFacts {
    let dir = path.parent().unwrap_or(Path::new("")).to_path_buf();
    let mod_dir = if is_mod_rs_like(path) {
        dir.clone()
    } else {
        dir.join(path.file_stem().unwrap_or_default())
    };
    let mut walker = Walker {
        dir,
        mod_dir,
        inline: Vec::new(),
        in_test: test,
        facts: FileFacts::default(),
    };
    walker.visit_file(file);
    walker.facts
}

/// The files that are test code: declared (by `mod` or `include!`) only from test code. Iterated to a
/// fixed point, since a test file's own declarations are test code too.
fn test_files(parsed: &BTreeMap<PathBuf, syn::File>) -> BTreeSet<PathBuf> {
    let mut test: BTreeSet<PathBuf> = BTreeSet::new();
    loop {
        let mut declared: BTreeMap<PathBuf, bool> = BTreeMap::new();
        for (path, file) in parsed {
            for d in walk(path, file, test.contains(path)).declarations {
                let found = d
                    .candidates
                    .iter()
                    .map(|c| normal(c))
                    .find(|c| parsed.contains_key(c));
                if let Some(target) = found {
                    *declared.entry(target).or_insert(true) &= d.test;
                }
            }
        }
        let now: BTreeSet<PathBuf> = declared
            .into_iter()
            .filter(|&(_, all_test)| all_test)
            .map(|(p, _)| p)
            .collect();
        if now == test {
            return test;
        }
        test = now;
    }
}

/// Every function over [`FUNCTION_REPORT_LINES`] and file over [`FILE_REPORT_LINES`] of the non-test
/// code in `sources` (path → text), or the first file that does not parse.
fn check(sources: &BTreeMap<PathBuf, String>) -> Result<Vec<Finding>, String> {
    Ok(check_and_list_tests(sources)?.0)
}

/// [`check`], and the files it took as test code as a whole.
fn check_and_list_tests(
    sources: &BTreeMap<PathBuf, String>,
) -> Result<(Vec<Finding>, BTreeSet<PathBuf>), String> {
    let parsed = sources
        .iter()
        .map(|(path, source)| Ok((path.clone(), parse(path, source)?)))
        .collect::<Result<BTreeMap<_, _>, String>>()?;
    let test = test_files(&parsed);
    let mut findings = Vec::new();
    for (path, file) in parsed.iter().filter(|(p, _)| !test.contains(*p)) {
        let source = &sources[path];
        let facts = walk(path, file, false);
        let lines: Vec<&str> = source.lines().collect();
        let mut is_test_line = vec![false; lines.len() + 1];
        for &(from, to) in &facts.test_lines {
            for flag in &mut is_test_line[from.min(lines.len())..=to.min(lines.len())] {
                *flag = true;
            }
        }
        let code_lines = (1..=lines.len()).filter(|&n| !is_test_line[n]).count();
        if code_lines > FILE_REPORT_LINES {
            let first_item = file.items.first().map_or(lines.len(), |i| line(i.span()));
            findings.push(Finding {
                place: path.display().to_string(),
                lines: code_lines,
                limit: FILE_LIMIT_LINES,
                reason: marker_in(&lines, 1, first_item.saturating_sub(1)),
            });
        }
        for (name, fn_line, n) in facts.functions {
            if n > FUNCTION_REPORT_LINES {
                let first = first_line_of_item(file, fn_line);
                findings.push(Finding {
                    place: format!("{}:{fn_line} fn {name}", path.display()),
                    lines: n,
                    limit: FUNCTION_LIMIT_LINES,
                    reason: marker_above(&lines, first, fn_line),
                });
            }
        }
    }
    findings.sort_by(|a, b| b.lines.cmp(&a.lines).then(a.place.cmp(&b.place)));
    Ok((findings, test))
}

/// The first line (first attribute or doc comment) of the function whose `fn` is on `fn_line`.
fn first_line_of_item(file: &syn::File, fn_line: usize) -> usize {
    struct Find {
        fn_line: usize,
        first: Option<usize>,
    }
    impl Find {
        fn consider(&mut self, attrs: &[syn::Attribute], sig: &syn::Signature) {
            if line(sig.span()) == self.fn_line {
                let first = attrs.iter().map(|a| line(a.span())).min();
                self.first = Some(first.unwrap_or(self.fn_line).min(self.fn_line));
            }
        }
    }
    impl<'ast> Visit<'ast> for Find {
        fn visit_item_fn(&mut self, f: &'ast syn::ItemFn) {
            self.consider(&f.attrs, &f.sig);
            syn::visit::visit_item_fn(self, f);
        }
        fn visit_impl_item_fn(&mut self, f: &'ast syn::ImplItemFn) {
            self.consider(&f.attrs, &f.sig);
            syn::visit::visit_impl_item_fn(self, f);
        }
        fn visit_trait_item_fn(&mut self, f: &'ast syn::TraitItemFn) {
            self.consider(&f.attrs, &f.sig);
            syn::visit::visit_trait_item_fn(self, f);
        }
    }
    let mut find = Find {
        fn_line,
        first: None,
    };
    find.visit_file(file);
    find.first.unwrap_or(fn_line)
}

/// Every `.rs` file under `root/dir`, keyed by its path relative to `root`.
fn read_tree(root: &Path, dir: &str, into: &mut BTreeMap<PathBuf, String>) {
    let mut stack = vec![PathBuf::from(dir)];
    while let Some(rel) = stack.pop() {
        let Ok(entries) = std::fs::read_dir(root.join(&rel)) else {
            continue;
        };
        for entry in entries {
            let name = entry.unwrap().file_name();
            let rel = rel.join(&name);
            if root.join(&rel).is_dir() {
                stack.push(rel);
            } else if rel.extension().is_some_and(|e| e == "rs") {
                let text = std::fs::read_to_string(root.join(&rel)).unwrap();
                into.insert(rel, text);
            }
        }
    }
}

#[test]
fn no_unexplained_long_function_or_file() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let mut sources = BTreeMap::new();
    for dir in ROOTS {
        read_tree(&root, dir, &mut sources);
    }
    assert!(sources.len() > 100, "found only {} files", sources.len());
    let (findings, test) = check_and_list_tests(&sources).unwrap();
    // Straight to the terminal: the findings are wanted whether the check passes or not.
    let mut out = std::io::stderr().lock();
    let _ = writeln!(
        out,
        "shape: {} files; functions over {FUNCTION_REPORT_LINES} lines and files over \
         {FILE_REPORT_LINES} lines of non-test code (limits {FUNCTION_LIMIT_LINES} and \
         {FILE_LIMIT_LINES}):",
        sources.len()
    );
    let test: Vec<String> = test.iter().map(|p| p.display().to_string()).collect();
    let _ = writeln!(out, "  test code as a whole: {}", test.join(", "));
    for f in &findings {
        let _ = writeln!(out, "  {f}");
    }
    let failing: Vec<String> = findings
        .iter()
        .filter(|f| f.fails())
        .map(|f| f.to_string())
        .collect();
    assert!(
        failing.is_empty(),
        "split these, or say above each why it reads better whole (`// {MARKER} …`):\n{}",
        failing.join("\n")
    );
}

#[cfg(test)]
mod planted {
    use super::*;

    fn sources(files: &[(&str, String)]) -> BTreeMap<PathBuf, String> {
        files
            .iter()
            .map(|(p, s)| (PathBuf::from(p), s.clone()))
            .collect()
    }

    /// A function whose `fn` line and closing brace enclose `body` lines, `lines` in all.
    fn function(name: &str, lines: usize) -> String {
        let body: String = (0..lines - 2)
            .map(|k| format!("    let _x{k} = {k};\n"))
            .collect();
        format!("pub fn {name}() {{\n{body}}}\n")
    }

    fn failing(findings: &[Finding]) -> Vec<String> {
        findings
            .iter()
            .filter(|f| f.fails())
            .map(|f| f.place.clone())
            .collect()
    }

    /// The case the brace-counting script missed: `mod tests;` near the top of a `mod.rs` does not
    /// make the rest of the file test code.
    #[test]
    fn a_101_line_function_after_mod_tests_fails() {
        let src = format!(
            "//! A module.\n\n#[cfg(test)]\nmod tests;\n\n/// Long.\n{}",
            function("long", 101)
        );
        let tests_rs = function("in_tests_rs", 300);
        let f = check(&sources(&[("m/mod.rs", src), ("m/tests.rs", tests_rs)])).unwrap();
        assert_eq!(failing(&f), ["m/mod.rs:7 fn long"], "{f:?}");
        assert_eq!(f[0].lines, 101);
    }

    #[test]
    fn a_100_line_function_passes_and_a_reason_allows_a_longer_one() {
        let at_limit = format!("{}\n{}", function("fits", 100), function("printed", 81));
        let f = check(&sources(&[("a.rs", at_limit)])).unwrap();
        assert!(failing(&f).is_empty(), "{f:?}");
        assert_eq!(f.len(), 2, "both are over 80 lines and printed: {f:?}");
        let allowed = format!(
            "// {MARKER} its steps share one table\n/// Doc.\n#[inline]\n{}",
            function("long", 150)
        );
        let f = check(&sources(&[("a.rs", allowed)])).unwrap();
        assert!(failing(&f).is_empty(), "{f:?}");
        assert_eq!(f[0].reason.as_deref(), Some("its steps share one table"));
        // A marker with no reason does not count.
        let empty = format!("// {MARKER}\n{}", function("long", 150));
        assert_eq!(
            failing(&check(&sources(&[("a.rs", empty)])).unwrap()).len(),
            1
        );
    }

    #[test]
    fn a_file_over_700_lines_of_non_test_code_fails_and_its_tests_do_not_count() {
        let code: String = (0..701)
            .map(|k| format!("const C{k}: u32 = {k};\n"))
            .collect();
        let f = check(&sources(&[("long.rs", code.clone())])).unwrap();
        assert_eq!(failing(&f), ["long.rs"], "{f:?}");
        assert_eq!(f[0].lines, 701);
        // 650 lines of code and a 300-line inline test module: 650 counted, printed, not failing.
        let tests: String = (0..298)
            .map(|k| format!("    const T{k}: u32 = {k};\n"))
            .collect();
        let mixed: String = (0..650)
            .map(|k| format!("const C{k}: u32 = {k};\n"))
            .collect::<String>()
            + "#[cfg(all(test, feature = \"x\"))]\nmod tests {\n"
            + &tests
            + "}\n";
        let f = check(&sources(&[("mixed.rs", mixed)])).unwrap();
        assert!(failing(&f).is_empty(), "{f:?}");
        assert_eq!(f[0].lines, 650);
        // A reason at the top of the file allows it, and a reason spans its comment lines.
        let allowed = format!("// {MARKER} it is one table\n// of constants\n{code}");
        let f = check(&sources(&[("long.rs", allowed)])).unwrap();
        assert_eq!(f[0].reason.as_deref(), Some("it is one table of constants"));
    }

    /// `tests.rs` is test code only when a test module declares it: a plain `mod tests;` is code.
    #[test]
    fn a_file_is_test_code_only_when_declared_from_test_code() {
        let tests_rs = function("helper", 120);
        let plain = "mod tests;\n".to_string();
        let f = check(&sources(&[
            ("lib.rs", plain),
            ("tests.rs", tests_rs.clone()),
        ]))
        .unwrap();
        assert_eq!(failing(&f), ["tests.rs:1 fn helper"], "{f:?}");
        // Declared from a test module's own file, `#[cfg(test)]` two levels up: test code.
        let root = "#[cfg(test)]\nmod a;\n".to_string();
        let a = "mod b;\n".to_string();
        let f = check(&sources(&[
            ("lib.rs", root),
            ("a.rs", a),
            ("a/b.rs", tests_rs),
        ]))
        .unwrap();
        assert!(f.is_empty(), "{f:?}");
        // `#[test]` functions and test items inside impl blocks are left out too.
        let src = format!(
            "struct S;\nimpl S {{\n    #[cfg(test)]\n{}}}\n#[test]\n{}",
            function("in_impl", 150),
            function("a_test", 150)
        );
        assert!(check(&sources(&[("s.rs", src)])).unwrap().is_empty());
    }

    /// The function the brace-counting script measured as 206 lines.
    #[test]
    fn braces_in_format_strings_are_not_code() {
        let src = r##"
fn c_initialiser(x: &str) -> String {
    let a = format!("{{ {{ {x} {{ {{ {{");
    let b = "{ { { { { { {";
    let c = r#"{{{{{ "{ " {{{"#;
    let d = '{';
    let e = "}}} }";
    format!("{a}{b}{c}{d}{e} }}")
}
"##;
        let f = check(&sources(&[("c.rs", src.to_string())])).unwrap();
        assert!(f.is_empty(), "{f:?}");
        // Measured at its true length: planted past the limit, it is reported with 8 + 100 lines.
        let grown = src.replace(
            "    let d",
            &format!("{}    let d", "    let _y = 1;\n".repeat(100)),
        );
        let f = check(&sources(&[("c.rs", grown)])).unwrap();
        assert_eq!(f.len(), 1, "{f:?}");
        assert_eq!(f[0].lines, 108);
    }
}

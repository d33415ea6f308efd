//! The page's [`Block`]s as Markdown and as self-contained HTML.

use super::page::Block;
use std::fmt::Write as _;

fn md_cell(s: &str) -> String {
    s.replace('|', "\\|")
}

/// Markdown.
pub(crate) fn to_markdown(blocks: &[Block]) -> String {
    let mut s = String::new();
    for b in blocks {
        match b {
            Block::Heading(l, t) => {
                let _ = writeln!(s, "{} {t}\n", "#".repeat(*l as usize));
            }
            Block::Para(t) => {
                let _ = writeln!(s, "{t}\n");
            }
            Block::Table { header, rows } => {
                let h: Vec<String> = header.iter().map(|c| md_cell(c)).collect();
                let _ = writeln!(s, "| {} |", h.join(" | "));
                let _ = writeln!(s, "|{}", "---|".repeat(header.len()));
                for r in rows {
                    let c: Vec<String> = r.iter().map(|c| md_cell(c)).collect();
                    let _ = writeln!(s, "| {} |", c.join(" | "));
                }
                s.push('\n');
            }
            Block::Image { src, alt } => {
                let _ = writeln!(s, "![{alt}]({src})\n");
            }
            Block::Pre(t) => {
                let _ = writeln!(s, "```text\n{}\n```\n", t.trim_end());
            }
        }
    }
    s
}

fn esc(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

/// Inline Markdown of the page's paragraphs (`code`, **bold**) in HTML.
fn inline_html(s: &str) -> String {
    let mut out = String::new();
    let mut code = false;
    let mut bold = false;
    let mut rest = s;
    while let Some(c) = rest.chars().next() {
        if rest.starts_with("**") {
            out.push_str(if bold { "</strong>" } else { "<strong>" });
            bold = !bold;
            rest = &rest[2..];
        } else if c == '`' {
            out.push_str(if code { "</code>" } else { "<code>" });
            code = !code;
            rest = &rest[1..];
        } else {
            out.push_str(&esc(&c.to_string()));
            rest = &rest[c.len_utf8()..];
        }
    }
    out
}

/// Self-contained HTML (images by relative path).
pub(crate) fn to_html(blocks: &[Block], title: &str) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><title>{}</title>\n<style>\
         body{{font-family:sans-serif;max-width:1250px;margin:2em auto;padding:0 1em}}\
         table{{border-collapse:collapse;margin:1em 0}}td,th{{border:1px solid #bbb;padding:3px 8px;\
         text-align:right;font-family:monospace}}th{{background:#eee}}img{{max-width:100%}}\
         pre{{background:#f6f6f6;padding:1em;overflow-x:auto}}</style></head><body>",
        esc(title)
    );
    for b in blocks {
        match b {
            Block::Heading(l, t) => {
                let _ = writeln!(s, "<h{l}>{}</h{l}>", esc(t));
            }
            Block::Para(t) => {
                let _ = writeln!(s, "<p>{}</p>", inline_html(t));
            }
            Block::Table { header, rows } => {
                s.push_str("<table>\n<tr>");
                for h in header {
                    let _ = write!(s, "<th>{}</th>", esc(h));
                }
                s.push_str("</tr>\n");
                for r in rows {
                    s.push_str("<tr>");
                    for c in r {
                        let _ = write!(s, "<td>{}</td>", esc(c));
                    }
                    s.push_str("</tr>\n");
                }
                s.push_str("</table>\n");
            }
            Block::Image { src, alt } => {
                let _ = writeln!(s, "<p><img src=\"{}\" alt=\"{}\"></p>", esc(src), esc(alt));
            }
            Block::Pre(t) => {
                let _ = writeln!(s, "<pre>{}</pre>", esc(t.trim_end()));
            }
        }
    }
    s.push_str("</body></html>\n");
    s
}

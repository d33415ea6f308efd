//! `host report`: a recorded session judged by a calibration, written as figures (PNG, SVG) and
//! `report.html` / `report.md` with Tables 1–4 and the navigation replay.

use super::data::{Compensation, ReportData, ReportError};
use super::figures::report_figures;
use super::markup::{to_html, to_markdown};
use super::navigation::render_navigation;
use super::page::{page, Block};
use super::plot::{self, Figure, Formats};
use recording::output_file::write_atomic;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// File name of the Markdown page.
pub const REPORT_MD: &str = "report.md";
/// File name of the HTML page (same content).
pub const REPORT_HTML: &str = "report.html";

/// What a report wrote ([`write_report`]).
#[derive(Clone, Debug)]
pub struct ReportSummary {
    /// The computed report.
    pub data: ReportData,
    /// The figures drawn (as data), in file order.
    pub figures: Vec<Figure>,
    /// Files written (figures, then `report.md` and `report.html`).
    pub files: Vec<PathBuf>,
    /// The HTML page: the one file to open.
    pub page: PathBuf,
    /// Warnings (no font, missing runs, …).
    pub warnings: Vec<crate::note::Note>,
}

impl ReportSummary {
    /// What the CLI prints as its result (the warnings go to stderr, one by one).
    pub fn render(&self) -> String {
        let mut s = String::new();
        let _ = writeln!(s, "Report: {}", self.page.display());
        let _ = write!(s, "{}", render_before_after(&self.data));
        if !self.data.navigation.is_empty() {
            let _ = writeln!(s, "{}", render_navigation(&self.data.navigation));
        }
        s
    }
}

/// One line per compensation level: the rms over segments of |output − theoretical| and the rms of
/// the segments' own noise, so the reader sees at once whether "after" is down at the noise.
pub(crate) fn render_before_after(data: &ReportData) -> String {
    let compared: Vec<_> = data
        .segments
        .iter()
        .filter(|r| r.truth_g.iter().all(|v| v.is_finite()))
        .collect();
    let mut s = String::new();
    if compared.is_empty() {
        return s;
    }
    let rms = |f: &dyn Fn(&super::SegmentRow) -> f64| {
        (compared.iter().map(|r| f(r).powi(2)).sum::<f64>() / compared.len() as f64).sqrt()
    };
    let _ = writeln!(
        s,
        "Outputs against the theoretical (this session's fitted attitudes), rms over {} segment(s) of |output − theoretical|:",
        compared.len()
    );
    for c in Compensation::ALL {
        let _ = writeln!(
            s,
            "  {:<26} {:>10.1} µg",
            c.label(),
            rms(&|r| shared::linalg::norm(&r.error_g(c))) * 1e6
        );
    }
    let _ = writeln!(
        s,
        "  {:<26} {:>10.1} µg",
        "the segments' own noise",
        rms(&|r| shared::linalg::norm(&r.sigma_g)) * 1e6
    );
    s
}

/// Writes the figures and the page of `data` into `out_dir`.
pub fn write_report(
    data: &ReportData,
    out_dir: &Path,
    session: &str,
    calibration: &str,
    formats: Formats,
) -> Result<ReportSummary, ReportError> {
    std::fs::create_dir_all(out_dir).map_err(|e| ReportError::Io(out_dir.to_path_buf(), e))?;
    let figs = report_figures(data);
    let mut files = Vec::new();
    let mut warnings = data.warnings.clone();
    let mut png = formats.png;
    for f in &figs {
        let out = plot::render(f, out_dir, formats)?;
        files.extend(out.files);
        png &= out.warnings.is_empty();
        for w in out.warnings {
            if !warnings.contains(&w) {
                warnings.push(w);
            }
        }
    }
    let stems: Vec<String> = figs.iter().map(|f| f.stem.clone()).collect();
    let mut blocks = page(data, session, calibration, &stems);
    if !png {
        // Point the page at the SVGs when no PNG was written.
        for b in &mut blocks {
            if let Block::Image { src, .. } = b {
                *src = src.replace(".png", ".svg");
            }
        }
    }
    // A report is regenerated in place (`--force` is implied: it is derived from the session),
    // but each page appears whole: a reader never opens half of one.
    let md = out_dir.join(REPORT_MD);
    write_atomic(&md, to_markdown(&blocks).as_bytes(), true)?;
    let html = out_dir.join(REPORT_HTML);
    write_atomic(
        &html,
        to_html(&blocks, "Calibration report").as_bytes(),
        true,
    )?;
    files.push(md);
    files.push(html.clone());
    Ok(ReportSummary {
        data: data.clone(),
        figures: figs,
        files,
        page: html,
        warnings,
    })
}

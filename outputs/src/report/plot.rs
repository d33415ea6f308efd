//! Figures of the calibration report, drawn with plotters to PNG and SVG.
//!
//! A figure is described as data first ([`Figure`]: panels of named series), so that what is plotted
//! can be compared with the tables printed next to it (the report's tests do exactly that), and only
//! then rendered by [`render`].
//!
//! Text needs a font. plotters is built without `font-kit` (no system font libraries), with `ab_glyph`
//! and one TrueType font compiled into the binary (`EMBEDDED_FONT`, DejaVu Sans, licence beside it
//! in `outputs/assets/fonts/`): every machine draws the same PNG and SVG, and nothing is looked up on the
//! file system or in the environment.

use crate::note::Note;
use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

pub use super::axes::{category_labels, decade_label, CategoryLabels, LEGEND_WIDTH_PX};
use super::axes::{decades, draw_legend, draw_markers, marker_shape, LABEL_PX};
use std::path::{Path, PathBuf};
use std::sync::OnceLock;

/// DejaVu Sans (Bitstream Vera licence, `outputs/assets/fonts/LICENSE-DejaVu.txt`), the figures' only
/// font: embedded so that a machine without fonts draws the same figures as any other.
pub(crate) static EMBEDDED_FONT: &[u8] = include_bytes!("../../assets/fonts/DejaVuSans.ttf");

/// The font family the embedded font is registered under.
pub(crate) const FAMILY: &str = "sans-serif";

/// Registers [`EMBEDDED_FONT`] for the figures once per process; the bytes registered, or `None` if
/// plotters refused them (a corrupt build; the figures are then drawn without text, SVG only).
pub(crate) fn ensure_font() -> Option<&'static [u8]> {
    static FONT: OnceLock<bool> = OnceLock::new();
    let registered = *FONT.get_or_init(|| {
        plotters::style::register_font(FAMILY, FontStyle::Normal, EMBEDDED_FONT).is_ok()
    });
    registered.then_some(EMBEDDED_FONT)
}

/// How a series is drawn.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SeriesStyle {
    /// A line through the points (one SVG `<polyline>`).
    Line,
    /// A line with a circle on every point.
    LineAndMarkers,
    /// Markers only (a shape per series: circle, triangle, square, cross), with vertical ±error
    /// bars when the series has them: measured data.
    Markers,
    /// A thin dashed line: a band's edge (±1σ of a fit).
    Dashed,
}

/// One plotted series.
#[derive(Clone, Debug, PartialEq)]
pub struct Series {
    /// Legend text.
    pub label: String,
    /// (x, y) points, in the panel's units.
    pub points: Vec<(f64, f64)>,
    /// Symmetric error (±) of each point, same units as y; drawn as vertical bars.
    pub error: Option<Vec<f64>>,
    /// Drawing style.
    pub style: SeriesStyle,
    /// Colour index into the figure palette.
    pub colour: usize,
}

/// One panel (a set of axes).
#[derive(Clone, Debug, PartialEq)]
pub struct Panel {
    /// Title above the panel.
    pub title: String,
    /// x-axis description.
    pub x_desc: String,
    /// y-axis description.
    pub y_desc: String,
    /// Category names for x = 0, 1, 2, …; `None`: a numeric x axis.
    pub x_categories: Option<Vec<String>>,
    /// Logarithmic x axis, ticks labelled at each decade (points with x ≤ 0 are left out).
    pub log_x: bool,
    /// Logarithmic y axis, ticks labelled at each decade (points with y ≤ 0 are left out).
    pub log_y: bool,
    /// The series.
    pub series: Vec<Series>,
}

/// A figure: panels stacked in a grid.
#[derive(Clone, Debug, PartialEq)]
pub struct Figure {
    /// File stem (`outputs` → `outputs.png`, `outputs.svg`).
    pub stem: String,
    /// Caption of the whole figure.
    pub title: String,
    /// Grid, (rows, columns); panels fill it row by row.
    pub grid: (usize, usize),
    /// Size, pixels.
    pub size: (u32, u32),
    /// The panels.
    pub panels: Vec<Panel>,
}

/// What [`render`] wrote.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct RenderOutcome {
    /// Files written.
    pub files: Vec<PathBuf>,
    /// Why something was not written or not drawn (e.g. no font: no PNG, no text).
    pub warnings: Vec<crate::note::Note>,
}

/// Why a figure could not be drawn.
#[derive(Debug, thiserror::Error)]
pub enum FigureError {
    /// plotters could not draw it (its backend's error, boxed: each backend has its own type).
    #[error("cannot draw {}", .path.display())]
    Draw {
        /// The file.
        path: PathBuf,
        /// plotters' error.
        #[source]
        source: DrawError,
    },
    /// The drawn file could not be put in place.
    #[error("cannot draw {}", .path.display())]
    Write {
        /// The file.
        path: PathBuf,
        /// The cause.
        #[source]
        source: std::io::Error,
    },
}

/// A plotters error of any backend.
pub(crate) type DrawError = Box<dyn std::error::Error + Send + Sync>;

/// Which files to write.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Formats {
    /// PNG (needs a font).
    pub png: bool,
    /// SVG.
    pub svg: bool,
}

impl Default for Formats {
    fn default() -> Self {
        Formats {
            png: true,
            svg: true,
        }
    }
}

/// Stroke width of the `index`-th of `count` line series of a panel: 2 for the last, 2 more for each
/// one before it.
pub(crate) fn line_width(index: usize, count: usize) -> u32 {
    2 + 2 * count.saturating_sub(index + 1) as u32
}

/// The palette: before (red), static-only (orange), full (blue), truth/reference (black), then more.
pub(crate) const PALETTE: [RGBColor; 6] = [
    RGBColor(200, 30, 30),
    RGBColor(230, 140, 0),
    RGBColor(20, 90, 200),
    RGBColor(0, 0, 0),
    RGBColor(40, 150, 60),
    RGBColor(130, 60, 170),
];

/// Draws `fig` into `dir` as `<stem>.png` and/or `<stem>.svg`.
pub fn render(fig: &Figure, dir: &Path, formats: Formats) -> Result<RenderOutcome, FigureError> {
    let text = ensure_font().is_some();
    render_with(fig, dir, formats, text)
}

/// [`render`] with text on or off (off: no font used; PNG is then not written).
pub(crate) fn render_with(
    fig: &Figure,
    dir: &Path,
    formats: Formats,
    text: bool,
) -> Result<RenderOutcome, FigureError> {
    let mut out = RenderOutcome::default();
    if formats.svg {
        let path = dir.join(format!("{}.svg", fig.stem));
        draw_in_place(fig, &path, text, FileKind::Svg)?;
        out.files.push(path);
        if !text {
            out.warnings.push(Note::SvgWithoutText {
                stem: fig.stem.clone(),
            });
        }
    }
    if formats.png {
        let path = dir.join(format!("{}.png", fig.stem));
        if text {
            draw_in_place(fig, &path, text, FileKind::Png)?;
            out.files.push(path);
        } else {
            out.warnings.push(Note::PngNotWritten { path });
        }
    }
    Ok(out)
}

/// A figure file's format.
#[derive(Clone, Copy)]
enum FileKind {
    Svg,
    Png,
}

/// Draws `fig` into `path` whole or not at all (`output_file::replace_through_path`): a figure is
/// regenerated in place, like its report.
fn draw_in_place(fig: &Figure, path: &Path, text: bool, kind: FileKind) -> Result<(), FigureError> {
    recording::output_file::replace_through_path(
        path,
        |temp| match kind {
            FileKind::Svg => draw_to_file(
                fig,
                SVGBackend::new(temp, fig.size).into_drawing_area(),
                path,
                text,
            ),
            FileKind::Png => draw_to_file(
                fig,
                BitMapBackend::new(temp, fig.size).into_drawing_area(),
                path,
                text,
            ),
        },
        |source| FigureError::Write {
            path: path.to_path_buf(),
            source,
        },
    )
}

/// Draws `fig` on a backend's root area and writes it out (the backend is dropped, closing the file).
fn draw_to_file<DB: DrawingBackend>(
    fig: &Figure,
    root: DrawingArea<DB, Shift>,
    path: &Path,
    text: bool,
) -> Result<(), FigureError>
where
    DB::ErrorType: 'static,
{
    let fail = |source: DrawError| FigureError::Draw {
        path: path.to_path_buf(),
        source,
    };
    draw(fig, &root, text).map_err(fail)?;
    root.present().map_err(|e| fail(err(e)))
}

fn err<E: std::error::Error + Send + Sync + 'static>(e: E) -> DrawError {
    Box::new(e)
}

fn draw<DB: DrawingBackend>(
    fig: &Figure,
    root: &DrawingArea<DB, Shift>,
    text: bool,
) -> Result<(), DrawError>
where
    DB::ErrorType: 'static,
{
    root.fill(&WHITE).map_err(err)?;
    let area = if text {
        root.titled(&fig.title, (FAMILY, 22)).map_err(err)?
    } else {
        root.margin(10, 10, 10, 10)
    };
    let cells = area.split_evenly(fig.grid);
    for (panel, cell) in fig.panels.iter().zip(cells.iter()) {
        draw_panel(panel, cell, text)?;
    }
    Ok(())
}

/// The y range of a panel, padded; log panels use positive values only.
fn y_range(panel: &Panel) -> (f64, f64) {
    let mut lo = f64::INFINITY;
    let mut hi = f64::NEG_INFINITY;
    for s in &panel.series {
        for (k, &(_, y)) in s.points.iter().enumerate() {
            let e = s
                .error
                .as_ref()
                .and_then(|e| e.get(k))
                .copied()
                .unwrap_or(0.0);
            for v in [y - e, y + e] {
                if !v.is_finite() || (panel.log_y && v <= 0.0) {
                    continue;
                }
                lo = lo.min(v);
                hi = hi.max(v);
            }
        }
    }
    if !lo.is_finite() || !hi.is_finite() {
        return if panel.log_y {
            (1e-6, 1.0)
        } else {
            (-1.0, 1.0)
        };
    }
    if panel.log_y {
        // Out to the decades around the data: a labelled tick at both ends.
        (
            10f64.powf((lo / 1.2).log10().floor()),
            10f64.powf((hi * 1.2).log10().ceil()),
        )
    } else {
        let span = (hi - lo).max(1e-12 * hi.abs().max(lo.abs()).max(1e-12));
        (lo - 0.08 * span, hi + 0.08 * span)
    }
}

fn x_range(panel: &Panel) -> (f64, f64) {
    if let Some(c) = &panel.x_categories {
        return (-0.5, c.len().max(1) as f64 - 0.5);
    }
    let xs = panel
        .series
        .iter()
        .flat_map(|s| s.points.iter().map(|p| p.0))
        .filter(|x| x.is_finite() && (!panel.log_x || *x > 0.0));
    let (lo, hi) = xs.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), x| {
        (a.min(x), b.max(x))
    });
    if !(lo.is_finite() && hi > lo) {
        return if panel.log_x { (0.1, 10.0) } else { (0.0, 1.0) };
    }
    if panel.log_x {
        // Out to the decades around the data, so that the axis has a labelled tick at both ends.
        (
            10f64.powf(lo.log10().floor()),
            10f64.powf(hi.log10().ceil()),
        )
    } else if panel.series.iter().any(|s| s.style == SeriesStyle::Markers) {
        // Markers at the ends are drawn whole.
        let pad = 0.03 * (hi - lo);
        (lo - pad, hi + pad)
    } else {
        (lo, hi)
    }
}

fn draw_panel<DB: DrawingBackend>(
    panel: &Panel,
    area: &DrawingArea<DB, Shift>,
    text: bool,
) -> Result<(), DrawError>
where
    DB::ErrorType: 'static,
{
    let (x0, x1) = x_range(panel);
    let (y0, y1) = y_range(panel);
    let legend = text && !panel.series.is_empty();
    let (plot_area, legend_area) = if legend {
        let w = area.dim_in_pixel().0;
        let (a, b) = area.split_horizontally(w.saturating_sub(LEGEND_WIDTH_PX) as i32);
        (a, Some(b))
    } else {
        (area.clone(), None)
    };
    let layout = panel.x_categories.as_ref().map(|c| {
        let w = plot_area.dim_in_pixel().0.saturating_sub(72 + 36);
        category_labels(c, w)
    });
    let mut builder = ChartBuilder::on(&plot_area);
    // The right margin leaves room for the last x tick's label, which is centred on the axis end.
    builder.margin(8).margin_right(28);
    if text {
        builder
            .caption(&panel.title, (FAMILY, 16))
            .x_label_area_size(layout.map_or(32, |l| l.area_px))
            .y_label_area_size(72);
    }
    let axes = Axes {
        panel,
        text,
        layout,
        x: (x0, x1),
        y: (y0, y1),
    };
    let a = &plot_area;
    match (panel.log_x, panel.log_y) {
        (false, false) => axes.draw(
            &mut builder.build_cartesian_2d(x0..x1, y0..y1).map_err(err)?,
            a,
        ),
        (false, true) => axes.draw(
            &mut builder
                .build_cartesian_2d(x0..x1, (y0..y1).log_scale())
                .map_err(err)?,
            a,
        ),
        (true, false) => axes.draw(
            &mut builder
                .build_cartesian_2d((x0..x1).log_scale(), y0..y1)
                .map_err(err)?,
            a,
        ),
        (true, true) => axes.draw(
            &mut builder
                .build_cartesian_2d((x0..x1).log_scale(), (y0..y1).log_scale())
                .map_err(err)?,
            a,
        ),
    }?;
    if let Some(l) = legend_area {
        draw_legend(panel, &l)?;
    }
    Ok(())
}

/// One panel's axes, whatever their scales.
struct Axes<'p> {
    panel: &'p Panel,
    text: bool,
    layout: Option<CategoryLabels>,
    x: (f64, f64),
    y: (f64, f64),
}

impl Axes<'_> {
    fn draw<'a, DB: DrawingBackend + 'a, X, Y>(
        &self,
        chart: &mut ChartContext<'a, DB, Cartesian2d<X, Y>>,
        area: &DrawingArea<DB, Shift>,
    ) -> Result<(), DrawError>
    where
        DB::ErrorType: 'static,
        X: Ranged<ValueType = f64> + plotters::coord::ranged1d::ValueFormatter<f64>,
        Y: Ranged<ValueType = f64> + plotters::coord::ranged1d::ValueFormatter<f64>,
    {
        let panel = self.panel;
        if self.text {
            let cats = panel.x_categories.clone();
            let step = self.layout.map_or(1, |l| l.step);
            let upright = self.layout.is_some_and(|l| l.upright);
            let log_x = panel.log_x;
            let xfmt = move |x: &f64| match &cats {
                Some(c) => {
                    let k = x.round();
                    let on_tick = (x - k).abs() < 1e-6 && k >= 0.0 && (k as usize) < c.len();
                    // Upright labels are drawn below (plotters centres a turned label on its tick).
                    if on_tick && (k as usize) % step == 0 && !upright {
                        c[k as usize].clone()
                    } else {
                        String::new()
                    }
                }
                None if log_x => decade_label(*x),
                None => format!("{x}"),
            };
            let log_y = panel.log_y;
            let yfmt = move |y: &f64| {
                if log_y {
                    decade_label(*y)
                } else {
                    format!("{y}")
                }
            };
            let mut mesh = chart.configure_mesh();
            mesh.x_desc(&panel.x_desc)
                .y_desc(&panel.y_desc)
                .label_style((FAMILY, LABEL_PX))
                .axis_desc_style((FAMILY, LABEL_PX))
                .max_light_lines(0)
                .x_label_formatter(&xfmt);
            if log_y {
                mesh.y_label_formatter(&yfmt)
                    .y_labels(decades(self.y.0, self.y.1) * 9);
            }
            if log_x {
                mesh.x_labels(decades(self.x.0, self.x.1) * 9);
            }
            if let Some(c) = &panel.x_categories {
                mesh.x_labels(c.len() + 1);
            }
            mesh.draw().map_err(err)?;
            if let (true, Some(c)) = (upright, &panel.x_categories) {
                // Turned 90°, reading downwards from just below each tick.
                let style = TextStyle::from((FAMILY, LABEL_PX).into_font())
                    .transform(FontTransform::Rotate90)
                    .pos(Pos::new(HPos::Left, VPos::Center));
                let (bx, by) = area.get_base_pixel();
                for (k, name) in c.iter().enumerate().step_by(step) {
                    let (px, py) = chart.backend_coord(&(k as f64, self.y.0));
                    area.draw(&Text::new(
                        name.clone(),
                        (px - bx, py - by + 8),
                        style.clone(),
                    ))
                    .map_err(err)?;
                }
            }
        }
        draw_series(chart, panel)
    }
}

fn draw_series<'a, DB: DrawingBackend + 'a, X, Y>(
    chart: &mut ChartContext<'a, DB, Cartesian2d<X, Y>>,
    panel: &Panel,
) -> Result<(), DrawError>
where
    DB::ErrorType: 'static,
    X: Ranged<ValueType = f64>,
    Y: Ranged<ValueType = f64>,
{
    let solid = |s: &Series| matches!(s.style, SeriesStyle::Line | SeriesStyle::LineAndMarkers);
    let n_lines = panel.series.iter().filter(|s| solid(s)).count();
    let (log_x, log_y) = (panel.log_x, panel.log_y);
    let mut line_no = 0;
    let mut marker_no = 0;
    for s in &panel.series {
        let colour = PALETTE[s.colour % PALETTE.len()];
        // Earlier lines are drawn wider, so a later line with the same data (static and full
        // compensation of a run without rotation) does not hide an earlier one.
        let width = line_width(line_no, n_lines);
        if solid(s) {
            line_no += 1;
        }
        let keep = |&(x, y): &(f64, f64)| {
            x.is_finite() && y.is_finite() && (!log_y || y > 0.0) && (!log_x || x > 0.0)
        };
        let pts: Vec<(f64, f64)> = s.points.iter().copied().filter(keep).collect();
        match s.style {
            SeriesStyle::Line => {
                chart
                    .draw_series(LineSeries::new(pts.clone(), colour.stroke_width(width)))
                    .map_err(err)?;
            }
            SeriesStyle::Dashed => {
                chart
                    .draw_series(DashedLineSeries::new(
                        pts.clone(),
                        6,
                        4,
                        colour.stroke_width(1),
                    ))
                    .map_err(err)?;
            }
            SeriesStyle::LineAndMarkers => {
                chart
                    .draw_series(
                        LineSeries::new(pts.clone(), colour.stroke_width(width)).point_size(3),
                    )
                    .map_err(err)?;
            }
            SeriesStyle::Markers => {
                if let Some(e) = &s.error {
                    let bars = s
                        .points
                        .iter()
                        .zip(e)
                        .filter(|(p, e)| keep(p) && e.is_finite())
                        .map(|(&(x, y), &e)| {
                            PathElement::new(vec![(x, y - e), (x, y + e)], colour.stroke_width(1))
                        });
                    chart.draw_series(bars).map_err(err)?;
                }
                draw_markers(chart, &pts, marker_shape(marker_no), colour)?;
                marker_no += 1;
            }
        }
    }
    Ok(())
}

/// Checks a PNG file's signature and reads its IHDR size, (width, height).
pub fn png_dimensions(bytes: &[u8]) -> Option<(u32, u32)> {
    const SIG: [u8; 8] = [0x89, b'P', b'N', b'G', 0x0d, 0x0a, 0x1a, 0x0a];
    if bytes.len() < 24 || bytes[..8] != SIG || &bytes[12..16] != b"IHDR" {
        return None;
    }
    let be = |b: &[u8]| u32::from_be_bytes([b[0], b[1], b[2], b[3]]);
    Some((be(&bytes[16..20]), be(&bytes[20..24])))
}

/// A `<polyline>` of an SVG file: its stroke colour (`#RRGGBB`), stroke width and number of points.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct SvgPolyline {
    /// Stroke colour as written, e.g. `#145AC8`.
    pub stroke: String,
    /// Stroke width as written.
    pub width: String,
    /// Number of points.
    pub points: usize,
}

/// The `<polyline>` elements of an SVG document written by [`render`] (for checking what was drawn).
pub fn svg_polylines(svg: &str) -> Vec<SvgPolyline> {
    let attr = |tag: &str, name: &str| -> String {
        let key = format!("{name}=\"");
        tag.find(&key)
            .map(|k| {
                let rest = &tag[k + key.len()..];
                rest[..rest.find('"').unwrap_or(rest.len())].to_string()
            })
            .unwrap_or_default()
    };
    svg.split("<polyline")
        .skip(1)
        .map(|rest| {
            let tag = &rest[..rest.find('>').unwrap_or(rest.len())];
            SvgPolyline {
                stroke: attr(tag, "stroke"),
                width: attr(tag, "stroke-width"),
                points: attr(tag, "points").split_whitespace().count(),
            }
        })
        .collect()
}

/// The SVG colour string of palette entry `i`.
pub fn palette_hex(i: usize) -> String {
    let c = PALETTE[i % PALETTE.len()];
    format!("#{:02X}{:02X}{:02X}", c.0, c.1, c.2)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::report::axes::CHAR_PX;

    fn figure() -> Figure {
        Figure {
            stem: "t".into(),
            title: "test figure".into(),
            grid: (1, 2),
            size: (600, 300),
            panels: vec![
                Panel {
                    title: "lines".into(),
                    x_desc: "t (s)".into(),
                    y_desc: "m".into(),
                    x_categories: None,
                    log_x: false,
                    log_y: true,
                    series: vec![
                        Series {
                            label: "a".into(),
                            points: (0..10).map(|k| (k as f64, (k * k) as f64)).collect(),
                            error: None,
                            style: SeriesStyle::Line,
                            colour: 0,
                        },
                        Series {
                            label: "b".into(),
                            points: (0..10).map(|k| (k as f64, k as f64)).collect(),
                            error: None,
                            style: SeriesStyle::Line,
                            colour: 1,
                        },
                    ],
                },
                Panel {
                    title: "markers".into(),
                    x_desc: "segment".into(),
                    y_desc: "µg".into(),
                    x_categories: Some(vec!["x+".into(), "x−".into(), "y+".into()]),
                    log_x: false,
                    log_y: false,
                    series: vec![Series {
                        label: "c".into(),
                        points: vec![(0.0, 1.0), (1.0, -2.0), (2.0, 0.5)],
                        error: Some(vec![0.5, 0.5, 0.5]),
                        style: SeriesStyle::Markers,
                        colour: 2,
                    }],
                },
            ],
        }
    }

    /// A figure appears whole or not at all: drawn again over itself, then onto a name that cannot
    /// be replaced (a directory), it leaves no temporary file and the directory as it was.
    #[test]
    fn figures_are_replaced_whole_and_a_failed_write_leaves_nothing_behind() {
        let dir = tempfile::tempdir().unwrap();
        let fig = figure();
        let names = |d: &Path| {
            let mut n: Vec<String> = std::fs::read_dir(d)
                .unwrap()
                .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
                .collect();
            n.sort();
            n
        };
        for _ in 0..2 {
            render(&fig, dir.path(), Formats::default()).unwrap();
            assert_eq!(names(dir.path()), ["t.png", "t.svg"]);
        }
        let blocked = tempfile::tempdir().unwrap();
        std::fs::create_dir(blocked.path().join("t.svg")).unwrap();
        let e = render(&fig, blocked.path(), Formats::default()).unwrap_err();
        assert!(e.to_string().contains("t.svg"), "{e}");
        assert_eq!(names(blocked.path()), ["t.svg"]);
        assert!(blocked.path().join("t.svg").is_dir());
    }

    #[test]
    fn renders_png_and_svg_and_without_font_svg_only() {
        let dir = tempfile::tempdir().unwrap();
        let fig = figure();
        let out = render(&fig, dir.path(), Formats::default()).unwrap();
        assert_eq!(out.files.len(), 2, "{out:?}");
        let png = std::fs::read(dir.path().join("t.png")).unwrap();
        assert_eq!(png_dimensions(&png), Some((600, 300)));
        let svg = std::fs::read_to_string(dir.path().join("t.svg")).unwrap();
        assert!(svg.trim_start().starts_with("<svg") && svg.trim_end().ends_with("</svg>"));
        // Two line series of 9 drawable points (log axis: y = 0 left out), the first drawn wider so
        // that the second cannot hide it, each also as a legend sample (width 2).
        let lines = svg_polylines(&svg);
        for c in [0, 1] {
            let width = line_width(c, 2).to_string();
            let mine: Vec<(usize, &str)> = lines
                .iter()
                .filter(|p| p.stroke == palette_hex(c))
                .map(|p| (p.points, p.width.as_str()))
                .collect();
            assert_eq!(mine, vec![(9, width.as_str()), (2, "2")], "colour {c}");
        }
        assert_eq!((line_width(0, 2), line_width(1, 2)), (4, 2));
        // Three markers and the legend's sample of them; three error bars (2-point polylines).
        assert_eq!(svg.matches("<circle").count(), 4);
        assert!(svg.contains("test figure") && svg.contains("µg"));

        let bare = tempfile::tempdir().unwrap();
        let out = render_with(&fig, bare.path(), Formats::default(), false).unwrap();
        assert_eq!(out.files, vec![bare.path().join("t.svg")]);
        assert_eq!(out.warnings.len(), 2);
        let svg = std::fs::read_to_string(bare.path().join("t.svg")).unwrap();
        assert!(!svg.contains("<text"));
        assert_eq!(svg.matches("<circle").count(), 3, "no legend without text");
        assert!(!bare.path().join("t.png").exists());
    }

    /// The PNG needs no font of the machine's: the font registered is the embedded one (the same
    /// bytes, not a copy read from somewhere), and the non-test code of this module has no way to
    /// look at the file system or the environment for one.
    #[test]
    fn png_is_drawn_with_the_embedded_font_and_no_font_lookup() {
        let font = ensure_font().expect("the embedded font registers");
        assert!(std::ptr::eq(font, EMBEDDED_FONT));
        assert_eq!(&EMBEDDED_FONT[..4], &[0, 1, 0, 0], "a TrueType file");
        let dir = tempfile::tempdir().unwrap();
        let out = render(&figure(), dir.path(), Formats::default()).unwrap();
        assert!(out.warnings.is_empty(), "{out:?}");
        let png = std::fs::read(dir.path().join("t.png")).unwrap();
        assert_eq!(png_dimensions(&png), Some((600, 300)));
        let src = include_str!("plot.rs");
        let code = &src[..src.find("#[cfg(test)]").unwrap()];
        for lookup in [
            "std::fs",
            "fs::read",
            "File::open",
            "read_dir",
            "env::var",
            "/usr/share",
            "/System/Library",
            "Windows",
        ] {
            assert!(!code.contains(lookup), "plot.rs looks for a font: {lookup}");
        }
    }

    /// The x coordinate of the SVG `<text>` element whose content is `label`.
    fn text_x(svg: &str, label: &str) -> Option<f64> {
        svg.split("<text").skip(1).find_map(|t| {
            let body = &t[t.find('>')? + 1..t.find("</text>")?];
            if body.trim() != label {
                return None;
            }
            let k = t.find(" x=\"")? + 4;
            t[k..k + t[k..].find('"')?].parse().ok()
        })
    }

    /// Every legend entry is in the column right of its panel, never over the data.
    #[test]
    fn legends_are_beside_the_data() {
        let dir = tempfile::tempdir().unwrap();
        let mut fig = figure();
        fig.size = (1200, 400);
        render(
            &fig,
            dir.path(),
            Formats {
                png: false,
                svg: true,
            },
        )
        .unwrap();
        let svg = std::fs::read_to_string(dir.path().join("t.svg")).unwrap();
        let cell = 1200.0 / 2.0;
        for (label, panel) in [("a", 0.0), ("b", 0.0), ("c", 1.0)] {
            let x = text_x(&svg, label).unwrap_or_else(|| panic!("no legend text {label}"));
            let column = cell * (panel + 1.0) - LEGEND_WIDTH_PX as f64;
            assert!(x > column && x < cell * (panel + 1.0), "{label} at x {x}");
        }
    }

    /// A legend label longer than the legend's column is wrapped inside the figure, not cut at
    /// its right edge (the residuals figure's "residual ± 1σ of the segment mean").
    #[test]
    fn long_legend_labels_stay_inside_the_figure() {
        let dir = tempfile::tempdir().unwrap();
        let mut fig = figure();
        fig.size = (1200, 400);
        let label = "residual ± 1σ of the segment mean";
        fig.panels[1].series[0].label = label.into();
        render(
            &fig,
            dir.path(),
            Formats {
                png: false,
                svg: true,
            },
        )
        .unwrap();
        let svg = std::fs::read_to_string(dir.path().join("t.svg")).unwrap();
        let lines = super::super::axes::legend_lines(label, super::super::axes::legend_chars());
        assert!(lines.len() > 1, "{lines:?}");
        for line in &lines {
            let x = text_x(&svg, line).unwrap_or_else(|| panic!("no legend line {line}"));
            let right = x + (line.chars().count() as u32 * CHAR_PX) as f64;
            assert!(
                right <= 1200.0,
                "'{line}' ends at x {right}, past the figure's 1200"
            );
        }
    }

    /// Category labels never run into each other: level when each fits its pitch, else upright and
    /// thinned to one per two line heights.
    #[test]
    fn category_labels_never_collide() {
        let names =
            |n: usize, len: usize| -> Vec<String> { (0..n).map(|_| "x".repeat(len)).collect() };
        let level = category_labels(&names(6, 4), 900);
        assert_eq!((level.upright, level.step), (false, 1));
        for (n, len, width) in [(30, 8, 900), (24, 8, 900), (200, 8, 900), (3, 60, 300)] {
            let l = category_labels(&names(n, len), width);
            let pitch = width / n as u32;
            if l.upright {
                assert!(pitch * l.step as u32 >= 2 * LABEL_PX, "{n} {len}: {l:?}");
                assert!(l.area_px >= (len as u32 * CHAR_PX).min(136), "{l:?}");
            } else {
                assert!(pitch >= len as u32 * CHAR_PX, "{n} {len}: {l:?}");
            }
        }
        assert_eq!(category_labels(&names(30, 8), 900).step, 1);
        assert!(category_labels(&names(200, 8), 900).step > 1);
    }

    #[test]
    fn log_axes_are_labelled_at_each_decade() {
        assert_eq!(decade_label(1e-3), "10⁻³");
        assert_eq!(decade_label(1.0), "10⁰");
        assert_eq!(decade_label(100.0), "10²");
        assert_eq!(decade_label(2e-3), "");
        assert_eq!(decade_label(0.0), "");
        let panel = Panel {
            title: String::new(),
            x_desc: String::new(),
            y_desc: String::new(),
            x_categories: None,
            log_x: true,
            log_y: true,
            series: vec![Series {
                label: "s".into(),
                points: vec![(0.003, 2e-5), (40.0, 7e-4)],
                error: None,
                style: SeriesStyle::Markers,
                colour: 0,
            }],
        };
        assert_eq!(x_range(&panel), (1e-3, 100.0));
        let (lo, hi) = y_range(&panel);
        assert!(
            (lo - 1e-5).abs() < 1e-18 && (hi - 1e-3).abs() < 1e-15,
            "{lo} {hi}"
        );
    }

    #[test]
    fn png_dimensions_rejects_non_png() {
        assert_eq!(png_dimensions(b"GIF89a............................"), None);
    }
}

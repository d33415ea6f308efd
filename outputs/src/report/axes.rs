//! The parts of a figure that keep it legible at a glance (drawn by [`super::plot`]): category
//! labels that never collide, decade labels of logarithmic axes, a marker shape per data series,
//! and the legend in its own column beside the data.

use super::plot::{Panel, SeriesStyle, FAMILY, PALETTE};
use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

fn err<E: std::fmt::Debug>(e: E) -> String {
    format!("{e:?}")
}

/// Width of the legend column right of every panel, pixels: the legend never covers data.
pub const LEGEND_WIDTH_PX: u32 = 200;
/// Font size of tick labels and legend entries, pixels.
pub(crate) const LABEL_PX: u32 = 12;
/// A generous width of one character of the label font, pixels (DejaVu Sans at 12 px: 7 at most
/// for the characters of the labels drawn here).
pub(crate) const CHAR_PX: u32 = 7;

/// How the category labels of an x axis are laid out so that none collides with the next: level
/// when they fit, else turned upright (all of them, up to one per 16 pixels), else every `step`-th.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct CategoryLabels {
    /// Turned 90°.
    pub upright: bool,
    /// Label every `step`-th category.
    pub step: usize,
    /// Height of the label area, pixels.
    pub area_px: u32,
}

/// The layout of `labels` on an axis `width_px` wide.
pub fn category_labels(labels: &[String], width_px: u32) -> CategoryLabels {
    let n = labels.len().max(1) as u32;
    let longest = labels.iter().map(|l| l.chars().count()).max().unwrap_or(1) as u32;
    let pitch = width_px / n;
    if pitch >= longest * CHAR_PX + 8 {
        return CategoryLabels {
            upright: false,
            step: 1,
            area_px: 40,
        };
    }
    // Upright, a label needs its line height (and some air) across the axis.
    let step = (2 * LABEL_PX).div_ceil(pitch.max(1)).max(1) as usize;
    CategoryLabels {
        upright: true,
        step,
        area_px: (longest * CHAR_PX + 24).min(160),
    }
}

/// The label of tick `v` of a logarithmic axis: a power of ten as "10⁻³", nothing between decades.
pub fn decade_label(v: f64) -> String {
    if v.is_nan() || v <= 0.0 {
        return String::new();
    }
    let e = v.log10();
    if (e - e.round()).abs() > 1e-6 {
        return String::new();
    }
    let sup = |c: char| match c {
        '-' => '⁻',
        '0' => '⁰',
        '1' => '¹',
        '2' => '²',
        '3' => '³',
        '4' => '⁴',
        '5' => '⁵',
        '6' => '⁶',
        '7' => '⁷',
        '8' => '⁸',
        _ => '⁹',
    };
    let exponent: String = format!("{}", e.round() as i64).chars().map(sup).collect();
    format!("10{exponent}")
}

/// Number of decades a log axis spans (one tick and label each).
pub fn decades(lo: f64, hi: f64) -> usize {
    ((hi / lo).log10().round().max(1.0) as usize) + 1
}

/// The marker of the `k`-th marker series of a panel: circle, triangle, square, cross, so that
/// series differ in shape as well as colour.
pub(crate) fn marker_shape(k: usize) -> usize {
    k % 4
}

/// Draws marker `shape` at each of `pts`.
pub(crate) fn draw_markers<'a, DB: DrawingBackend + 'a, X, Y>(
    chart: &mut ChartContext<'a, DB, Cartesian2d<X, Y>>,
    pts: &[(f64, f64)],
    shape: usize,
    colour: RGBColor,
) -> Result<(), String>
where
    X: Ranged<ValueType = f64>,
    Y: Ranged<ValueType = f64>,
{
    let p = pts.iter().copied();
    match shape {
        0 => chart
            .draw_series(p.map(|p| Circle::new(p, 4, colour.filled())))
            .map(|_| ()),
        1 => chart
            .draw_series(p.map(|p| TriangleMarker::new(p, 5, colour.filled())))
            .map(|_| ()),
        2 => {
            chart
                .draw_series(p.map(|p| {
                    EmptyElement::at(p) + Rectangle::new([(-4, -4), (4, 4)], colour.filled())
                }))
                .map(|_| ())
        }
        _ => chart
            .draw_series(p.map(|p| Cross::new(p, 4, colour.stroke_width(2))))
            .map(|_| ()),
    }
    .map_err(err)
}

/// The legend in its own column right of the panel: one entry per distinct label, its sample
/// drawn as the series is (a line, a dashed line, or the series' marker).
pub(crate) fn draw_legend<DB: DrawingBackend>(
    panel: &Panel,
    area: &DrawingArea<DB, Shift>,
) -> Result<(), String> {
    let mut seen: Vec<&str> = Vec::new();
    let mut marker_no = 0;
    let mut y = 44;
    let style =
        TextStyle::from((FAMILY, LABEL_PX).into_font()).pos(Pos::new(HPos::Left, VPos::Center));
    for s in &panel.series {
        let shape = marker_shape(marker_no);
        if s.style == SeriesStyle::Markers {
            marker_no += 1;
        }
        if s.label.is_empty() || seen.contains(&s.label.as_str()) {
            continue;
        }
        seen.push(&s.label);
        let colour = PALETTE[s.colour % PALETTE.len()];
        let (x0, x1) = (6, 30);
        match s.style {
            SeriesStyle::Line | SeriesStyle::LineAndMarkers => {
                area.draw(&PathElement::new(
                    vec![(x0, y), (x1, y)],
                    colour.stroke_width(2),
                ))
                .map_err(err)?;
            }
            SeriesStyle::Dashed => {
                for k in 0..3 {
                    let a = x0 + 9 * k;
                    area.draw(&PathElement::new(
                        vec![(a, y), (a + 5, y)],
                        colour.stroke_width(1),
                    ))
                    .map_err(err)?;
                }
            }
            SeriesStyle::Markers => {
                let c = ((x0 + x1) / 2, y);
                match shape {
                    0 => area.draw(&Circle::new(c, 4, colour.filled())),
                    1 => area.draw(&TriangleMarker::new(c, 5, colour.filled())),
                    2 => area.draw(&Rectangle::new(
                        [(c.0 - 4, y - 4), (c.0 + 4, y + 4)],
                        colour.filled(),
                    )),
                    _ => area.draw(&Cross::new(c, 4, colour.stroke_width(2))),
                }
                .map_err(err)?;
            }
        }
        // A label longer than the column is wrapped at its spaces, never cut at the figure's edge.
        for line in legend_lines(&s.label, legend_chars()) {
            area.draw(&Text::new(line, (x1 + 8, y), style.clone()))
                .map_err(err)?;
            y += 16;
        }
        y += 2;
    }
    Ok(())
}

/// How many characters of a legend label fit in the legend column right of its marker.
pub(crate) fn legend_chars() -> usize {
    ((LEGEND_WIDTH_PX - 38 - 6) / CHAR_PX) as usize
}

/// `label` in lines of at most `width` characters, broken at spaces (a longer word stands alone).
pub(crate) fn legend_lines(label: &str, width: usize) -> Vec<String> {
    let mut lines: Vec<String> = Vec::new();
    for word in label.split(' ') {
        match lines.last_mut() {
            Some(l) if l.chars().count() + 1 + word.chars().count() <= width => {
                l.push(' ');
                l.push_str(word);
            }
            _ => lines.push(word.to_string()),
        }
    }
    lines
}

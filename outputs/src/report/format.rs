//! The one way a value and its 1σ are printed, in the terminal text and in the report's tables.

use shared::OutputUnit;

/// Decimals of a value in the output unit: µV in volts, thousandths of a count in LSB, µm/s² in m/s²,
/// 0.1 µg in g.
pub(crate) fn out_digits(unit: OutputUnit) -> usize {
    match unit {
        OutputUnit::Volts => 6,
        OutputUnit::Lsb => 3,
        OutputUnit::MetresPerSecondSquared => 6,
        OutputUnit::StandardGravity => 7,
    }
}

/// `v ± s` with at least `digits` decimals, and more when needed to show two significant digits of
/// the 1σ (a bias known to 0.1 µV must not print as "± 0.000000").
pub(crate) fn pm(v: f64, s: f64, digits: usize) -> String {
    if s.is_finite() {
        let needed = if s > 0.0 {
            (1.0 - s.log10().floor()).max(0.0) as usize
        } else {
            0
        };
        let digits = digits.max(needed).min(10);
        format!("{v:.digits$} ± {s:.digits$}")
    } else {
        format!("{v:.digits$} ± ∞")
    }
}

/// [`pm`] when the 1σ is known; the value alone, marked, when it is not (a calibration file without
/// an `[uncertainty]` table).
pub(crate) fn pm_opt(v: f64, s: Option<f64>, digits: usize) -> String {
    match s {
        Some(s) => pm(v, s, digits),
        None => format!("{v:.digits$} (no σ)"),
    }
}

/// The reference point of the lever arms, in words (never a type's name).
pub(crate) fn reference_point(r: &shared::ReferencePoint) -> String {
    match r {
        shared::ReferencePoint::TableAxis => "the point on the table's spin axis".into(),
        shared::ReferencePoint::Centroid => "the centroid of the three sensing points".into(),
        shared::ReferencePoint::BodyPoint { offset_m } => format!(
            "the body point ({:+.3}, {:+.3}, {:+.3}) mm from the table-axis point",
            offset_m[0] * 1e3,
            offset_m[1] * 1e3,
            offset_m[2] * 1e3
        ),
    }
}

/// A value in g to 0.1 µg, or "—" when there is none (NaN).
pub(crate) fn g_or_dash(v: f64) -> String {
    if v.is_finite() {
        format!("{v:+.6}")
    } else {
        "—".into()
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn sigma_keeps_two_significant_digits() {
        assert_eq!(super::pm(2.405098123, 1.3e-7, 6), "2.40509812 ± 0.00000013");
        assert_eq!(super::pm(0.39496, 2.0e-3, 6), "0.394960 ± 0.002000");
        assert_eq!(super::pm(1.0, f64::INFINITY, 3), "1.000 ± ∞");
        assert_eq!(super::pm_opt(1.0, None, 3), "1.000 (no σ)");
    }
}

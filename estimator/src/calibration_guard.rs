//! What a calibration must be before it meets anything — a recording (`host apply`, `noise`,
//! `report`), a device (`host flash`) or another tool (`host export`): its scale factors positive.
//!
//! A negative scale factor compensates its axis with the wrong sign while the magnitude checks
//! (|f| ≈ 1 g at rest) still pass, so it is a wrong result, not a surprise: the convention of
//! `docs/model.md` §2 has positive scale factors, a reversed axis being an installation angle near
//! 180°. A zero one has no inverse.

use shared::Calibration;

/// A scale factor that no device or tool can use as it stands.
#[derive(Clone, Copy, Debug, PartialEq, thiserror::Error)]
#[error(
    "accelerometer {axis} has a {} scale factor ({value} {unit} per g); scale factors are positive \
     by convention (a reversed axis is an installation angle near 180°): correct the calibration \
     file or recalibrate",
    if *.value == 0.0 { "zero" } else { "negative" }
)]
pub struct ScaleError {
    /// "x", "y" or "z".
    pub axis: &'static str,
    /// The scale factor, output unit per g.
    pub value: f64,
    /// The output unit's symbol.
    pub unit: &'static str,
}

/// Refuses a calibration whose scale factor on some axis is zero or negative (NaN is left to the
/// parameters' own finiteness check, which names it as such).
pub fn check_scales(cal: &Calibration) -> Result<(), ScaleError> {
    let s = &cal.statics;
    for (i, k) in s.scale_out_per_g.iter().enumerate() {
        if *k <= 0.0 {
            return Err(ScaleError {
                axis: shared::params::axis_name(i),
                value: *k,
                unit: s.output_unit.symbol(),
            });
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The paper's unit passes; each axis negated or zeroed is refused, naming the axis, its value
    /// and what is wrong.
    #[test]
    fn negative_and_zero_scales_are_refused_by_axis() {
        let good = shared::params::PAPER_UNIT;
        assert!(check_scales(&good).is_ok());
        for i in 0..3 {
            for (value, word) in [
                (-good.statics.scale_out_per_g[i], "negative"),
                (0.0, "zero"),
            ] {
                let mut bad = good;
                bad.statics.scale_out_per_g[i] = value;
                let e = check_scales(&bad).unwrap_err();
                assert_eq!(e.axis, ["x", "y", "z"][i]);
                assert!(
                    e.to_string().contains(&format!("{word} scale factor")),
                    "{e}"
                );
            }
        }
    }
}

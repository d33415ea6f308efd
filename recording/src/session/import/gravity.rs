//! Whether the accelerometer's stated unit fits its data: gravity's magnitude, the median over all
//! rows of a mostly still hand-held recording, must read as 1 g in that unit (m/s² and g), and
//! counts or volts must not read it as 1 g of a physical unit. A refusal says which unit the values
//! look like, in the caller's spelling of the option.

use super::{ImportError, Recording};
use crate::spelling::{Spelling, UserOption};
use shared::OutputUnit;

/// Rows averaged before their magnitude is taken.
const BLOCK_ROWS: usize = 16;

/// The median over blocks of [`BLOCK_ROWS`] rows of |mean acc|: gravity's magnitude in the
/// recording's unit. The mean of a block is what the unit feels once vibration averages out: a
/// vehicle's log whose rows shake by a g or more about gravity (a flight) still reads 1 g, where the
/// median of the rows' own magnitudes would read up to 1.7 g.
fn median_magnitude(rec: &Recording) -> f64 {
    let mut mags: Vec<f64> = rec
        .acc
        .chunks(BLOCK_ROWS)
        .map(|b| {
            let n = b.len() as f64;
            // About the first row: exact for a block of equal rows, whatever their size.
            let mean: [f64; 3] = core::array::from_fn(|j| {
                b[0][j] + b.iter().map(|v| v[j] - b[0][j]).sum::<f64>() / n
            });
            shared::linalg::norm(&mean)
        })
        .collect();
    mags.sort_by(f64::total_cmp);
    mags[mags.len() / 2]
}

/// Counts and volts have no expected gravity, but data whose gravity reads as 1 g in m/s² or in g
/// (within 2 %) are physical units given as counts or volts: no ADC or digital part reads gravity as
/// 9.81 or 1.00 of its own unit by chance.
fn check_not_physical(rec: &Recording, unit: OutputUnit, sp: Spelling) -> Result<(), ImportError> {
    let median = median_magnitude(rec);
    let near = |x: f64| (median / x - 1.0).abs() < 0.02;
    let acc_unit = |u| sp.given(UserOption::AccUnit, u);
    let hint = if near(shared::STANDARD_GRAVITY_M_S2) {
        format!(" (the values are gravity in m/s²: {})", acc_unit("m/s2"))
    } else if near(1.0) {
        format!(" (the values are gravity in g: {})", acc_unit("g"))
    } else {
        return Ok(());
    };
    Err(ImportError::UnitMismatch {
        median,
        unit: unit.symbol(),
        expected: None,
        hint,
        spelling: sp,
    })
}

/// Gravity's magnitude must be about 1 g in the stated unit (for m/s² and g; LSB and V have no
/// expected value). The median over all rows is gravity's: a hand-held recording is mostly still.
pub(super) fn check_gravity(
    rec: &Recording,
    unit: OutputUnit,
    sp: Spelling,
) -> Result<(), ImportError> {
    let expected = match unit {
        OutputUnit::MetresPerSecondSquared => shared::STANDARD_GRAVITY_M_S2,
        OutputUnit::StandardGravity => 1.0,
        OutputUnit::Lsb | OutputUnit::Volts => return check_not_physical(rec, unit, sp),
    };
    let median = median_magnitude(rec);
    let ratio = median / expected;
    if (0.8..=1.25).contains(&ratio) {
        return Ok(());
    }
    let acc_unit = |u| sp.given(UserOption::AccUnit, u);
    let hint = if (ratio * shared::STANDARD_GRAVITY_M_S2 - 1.0).abs() < 0.2 {
        format!(" (the values look like g: {})", acc_unit("g"))
    } else if (ratio / shared::STANDARD_GRAVITY_M_S2 - 1.0).abs() < 0.2 {
        format!(" (the values look like m/s²: {})", acc_unit("m/s2"))
    } else {
        format!(" (raw counts or volts? {} or V)", acc_unit("LSB"))
    };
    Err(ImportError::UnitMismatch {
        median,
        unit: unit.symbol(),
        expected: Some(expected),
        hint,
        spelling: sp,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A vehicle's log: gravity on z and a vibration of ±1 g on each axis, its sign alternating from
    /// row to row, so that each block of 16 rows averages it out exactly. Each row's magnitude is
    /// √(1² + 1² + 0²) g or √(1² + 1² + 2²) g, never 1 g; the blocks' means are gravity itself.
    fn vibrating(rows: usize) -> Recording {
        let g = shared::STANDARD_GRAVITY_M_S2;
        let acc = (0..rows)
            .map(|k| {
                let s = if k % 2 == 0 { g } else { -g };
                [s, -s, -g + s]
            })
            .collect();
        Recording {
            acc,
            ..Recording::default()
        }
    }

    #[test]
    fn a_vibrating_log_in_m_s2_reads_as_gravity() {
        let rec = vibrating(1600);
        let rows: Vec<f64> = rec.acc.iter().map(shared::linalg::norm).collect();
        assert!(rows
            .iter()
            .all(|m| *m > 1.4 * shared::STANDARD_GRAVITY_M_S2));
        assert!((median_magnitude(&rec) - shared::STANDARD_GRAVITY_M_S2).abs() < 1e-9);
        let sp = crate::testkit::SPELLING;
        assert!(check_gravity(&rec, OutputUnit::MetresPerSecondSquared, sp).is_ok());
        // The same numbers said to be in g are still refused, and the hint names m/s².
        let e = check_gravity(&rec, OutputUnit::StandardGravity, sp).unwrap_err();
        assert!(e.to_string().contains("m/s2"), "{e}");
    }
}

//! Temperature statistics of one segment (docs/model.md §9): the moments that let the temperature fit
//! be an exact least-squares fit over every sample, in one streaming pass and constant memory.
//!
//! At a fixed attitude the model of each output is a polynomial of degree ≤ 3 in the temperature
//! (`U_i = (1 + S_i(ΔT))·m_i·f + u0_i + P_i(ΔT)`), so the sum of squared residuals of any such
//! polynomial `β` in `x` is `Σu² − 2βᵀb + βᵀGβ`, with `G_jk = Σ x^(j+k)` and `b_k = Σ u x^k`. Those
//! sums are kept. `x = (T − ORIGIN_C)/SCALE_C` keeps the powers near 1 so the sums stay well
//! conditioned; outputs are shifted by the segment's first sample like [`super::stats`].

/// The fixed origin of the accumulated powers, °C.
pub const ORIGIN_C: f64 = 25.0;
/// The scale of the accumulated powers, °C: `x = (T − ORIGIN_C)/SCALE_C`.
pub const SCALE_C: f64 = 50.0;
/// Number of polynomial coefficients (degree 3 and the constant).
pub const TERMS: usize = 4;

/// The temperature moments of one segment's accepted rows.
#[derive(Clone, Debug, PartialEq)]
pub struct ThermalStats {
    /// Rows with a temperature.
    pub count: u64,
    /// The outputs of the first row, subtracted from every output before summing, output unit.
    pub u_shift: [f64; 3],
    /// `Σ x^k`, `k = 0..=6`.
    pub sum_x_pow: [f64; 2 * TERMS - 1],
    /// `Σ (u_i − u_shift_i) x^k`, `k = 0..=3`, per output.
    pub sum_u_x_pow: [[f64; TERMS]; 3],
    /// `Σ (u_i − u_shift_i)²`, per output.
    pub sum_u2: [f64; 3],
    /// Lowest and highest temperature read, °C.
    pub min_c: f64,
    /// See `min_c`.
    pub max_c: f64,
}

impl ThermalStats {
    /// The mean temperature, °C.
    pub fn mean_c(&self) -> f64 {
        ORIGIN_C + SCALE_C * self.sum_x_pow[1] / self.sum_x_pow[0]
    }

    /// The Gram matrix `G_jk = Σ x^(j+k)`.
    pub fn gram(&self) -> [[f64; TERMS]; TERMS] {
        std::array::from_fn(|j| std::array::from_fn(|k| self.sum_x_pow[j + k]))
    }

    /// `Σ (u_i − shift − β(x))²` for a polynomial `β` in `x` (coefficients of `x^0..x^3`) of output
    /// `i`, the shift included in `β_0` by the caller.
    pub fn residual_sum_squares(&self, i: usize, beta: &[f64; TERMS]) -> f64 {
        let g = self.gram();
        let b = &self.sum_u_x_pow[i];
        let mut quad = 0.0;
        for j in 0..TERMS {
            for k in 0..TERMS {
                quad += beta[j] * g[j][k] * beta[k];
            }
        }
        let lin: f64 = (0..TERMS).map(|k| beta[k] * b[k]).sum();
        self.sum_u2[i] - 2.0 * lin + quad
    }

    /// The mean of `x'^k`, `k = 0..=3`, with `x' = (T − reference_c)/SCALE_C`.
    pub fn mean_powers_about(&self, reference_c: f64) -> [f64; TERMS] {
        let d = (reference_c - ORIGIN_C) / SCALE_C;
        let n = self.sum_x_pow[0];
        // E[(x − d)^k] = Σ_j C(k, j) E[x^j] (−d)^(k−j).
        std::array::from_fn(|k| {
            (0..=k)
                .map(|j| binomial(k, j) * self.sum_x_pow[j] / n * (-d).powi((k - j) as i32))
                .sum()
        })
    }
}

/// `C(n, k)` for the small `n` of a cubic.
pub fn binomial(n: usize, k: usize) -> f64 {
    (0..k).fold(1.0, |acc, j| acc * (n - j) as f64 / (j + 1) as f64)
}

/// Streaming accumulator for [`ThermalStats`].
#[derive(Clone, Debug)]
pub struct ThermalAccumulator {
    n: u64,
    u_shift: [f64; 3],
    sx: [f64; 2 * TERMS - 1],
    sux: [[f64; TERMS]; 3],
    suu: [f64; 3],
    min_c: f64,
    max_c: f64,
}

impl Default for ThermalAccumulator {
    fn default() -> Self {
        ThermalAccumulator {
            n: 0,
            u_shift: [0.0; 3],
            sx: [0.0; 2 * TERMS - 1],
            sux: [[0.0; TERMS]; 3],
            suu: [0.0; 3],
            min_c: f64::INFINITY,
            max_c: f64::NEG_INFINITY,
        }
    }
}

impl ThermalAccumulator {
    /// Adds one row; the caller has checked that every value is finite.
    #[inline]
    pub fn push(&mut self, u: &[f64; 3], temp_c: f64) {
        if self.n == 0 {
            self.u_shift = *u;
        }
        self.n += 1;
        self.min_c = self.min_c.min(temp_c);
        self.max_c = self.max_c.max(temp_c);
        let x = (temp_c - ORIGIN_C) / SCALE_C;
        let mut p = 1.0;
        let mut powers = [0.0; 2 * TERMS - 1];
        for (slot, sum) in powers.iter_mut().zip(&mut self.sx) {
            *slot = p;
            *sum += p;
            p *= x;
        }
        for i in 0..3 {
            let du = u[i] - self.u_shift[i];
            self.suu[i] += du * du;
            for k in 0..TERMS {
                self.sux[i][k] += du * powers[k];
            }
        }
    }

    /// The statistics, or `None` when no row had a temperature.
    pub fn finish(&self) -> Option<ThermalStats> {
        (self.n > 0).then_some(ThermalStats {
            count: self.n,
            u_shift: self.u_shift,
            sum_x_pow: self.sx,
            sum_u_x_pow: self.sux,
            sum_u2: self.suu,
            min_c: self.min_c,
            max_c: self.max_c,
        })
    }
}

/// Fastest change of a unit's temperature reading that is physical, °C/s: chambers ramp at a few
/// °C/min and a board's self-heating takes minutes; a single reading that jumps further is a glitch
/// of the sensor or its bus (an all-ones word reads as 150 °C on many parts).
pub(crate) const MAX_TEMP_RATE_C_PER_S: f64 = 5.0;

/// Allowed change between two readings regardless of the time between them, °C (the reading's own
/// noise and quantisation).
pub(crate) const TEMP_JUMP_FLOOR_C: f64 = 1.0;

/// Whether the temperature reading `(t_s, °C)` is a glitch: it jumps from the readings before and
/// after it (file order, any segment; `None` at either end) by more than [`MAX_TEMP_RATE_C_PER_S`]
/// allows over the time between them. A real change (a soak step) is followed by the next reading;
/// a glitch is not. Left out, one glitch neither stretches the valid temperature range nor bends
/// the temperature fit.
pub(crate) fn is_glitch(
    before: Option<(f64, f64)>,
    reading: (f64, f64),
    after: Option<(f64, f64)>,
) -> bool {
    let jumps = |other: (f64, f64)| {
        let allowed = TEMP_JUMP_FLOOR_C + MAX_TEMP_RATE_C_PER_S * (reading.0 - other.0).abs();
        let jump = (reading.1 - other.1).abs();
        jump.is_nan() || jump > allowed
    };
    let after = after.filter(|a| a.1.is_finite());
    match (before.map(jumps), after.map(jumps)) {
        (Some(b), Some(a)) => b && a,
        (None, Some(j)) | (Some(j), None) => j,
        (None, None) => false,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn one_glitch_is_left_out_and_a_real_step_is_followed() {
        let reading = |k: usize| {
            let t = k as f64 * 0.01;
            let c = match k {
                0 | 40 => 150.0,
                60..=99 => 45.0,
                _ => 25.0 + 0.01 * t,
            };
            (t, c)
        };
        let mut before = None;
        let mut glitches = Vec::new();
        for k in 0..100 {
            let after = (k < 99).then(|| reading(k + 1));
            if is_glitch(before, reading(k), after) {
                glitches.push(k);
            } else {
                before = Some(reading(k));
            }
        }
        // The first reading and the one in the middle; the step at 60 is followed.
        assert_eq!(glitches, [0, 40]);
        // Slow enough over a long time: no glitch.
        assert!(!is_glitch(
            Some((0.0, 25.0)),
            (10.0, 60.0),
            Some((10.1, 60.0))
        ));
    }

    /// Rows of a ramp from 0 to 50 °C whose output 0 is an exact cubic in T.
    fn ramp() -> (ThermalStats, [f64; TERMS]) {
        // u = 2 + 0.01 x + 0.002 x² − 0.0005 x³ with x = (T − 25)/50.
        let beta = [2.0, 0.01, 0.002, -0.0005];
        let mut acc = ThermalAccumulator::default();
        for k in 0..=500 {
            let t = k as f64 * 0.1;
            let x = (t - ORIGIN_C) / SCALE_C;
            let u0 = beta[0] + x * (beta[1] + x * (beta[2] + x * beta[3]));
            acc.push(&[u0, 1.0, 0.0], t);
        }
        (acc.finish().unwrap(), beta)
    }

    #[test]
    fn an_exact_polynomial_has_zero_residual_and_a_wrong_one_does_not() {
        let (st, mut beta) = ramp();
        beta[0] -= st.u_shift[0];
        let rss = st.residual_sum_squares(0, &beta);
        assert!(rss.abs() < 1e-12, "{rss}");
        // Off by 1e-3 in the constant: 501 rows × 1e-6.
        beta[0] += 1e-3;
        let rss = st.residual_sum_squares(0, &beta);
        assert!((rss - 501e-6).abs() < 1e-9, "{rss}");
        assert_eq!(st.count, 501);
        assert_eq!((st.min_c, st.max_c), (0.0, 50.0));
        assert!((st.mean_c() - 25.0).abs() < 1e-9);
    }

    #[test]
    fn mean_powers_shift_to_another_reference() {
        let (st, _) = ramp();
        // About 5 °C: x' = (T − 5)/50 over T = 0..50 in steps of 0.1.
        let direct: Vec<f64> = (0..TERMS)
            .map(|k| {
                (0..=500)
                    .map(|j| ((j as f64 * 0.1 - 5.0) / SCALE_C).powi(k as i32))
                    .sum::<f64>()
                    / 501.0
            })
            .collect();
        let shifted = st.mean_powers_about(5.0);
        for k in 0..TERMS {
            assert!((shifted[k] - direct[k]).abs() < 1e-12, "k {k}");
        }
        assert_eq!(binomial(3, 2), 3.0);
    }
}

#[cfg(test)]
mod recording_tests {
    use crate::session::{read_session, Plan, ReadOptions, SessionWriter};

    const PLAN_V2: &str = r#"
format_version = 3
output_unit = "V"
sample_rate_hz = 100
[[segment]]
name = "x+"
up_b = [1, 0, 0]
temp_c = 10
[[segment]]
name = "x-"
up_b = [-1, 0, 0]
"#;

    #[test]
    fn version_3_round_trips_with_temperature_and_version_1_is_told_apart() {
        let dir = tempfile::tempdir().unwrap();
        let plan = Plan::parse(PLAN_V2).unwrap();
        let mut w = SessionWriter::create(dir.path(), &plan, false).unwrap();
        // A version 3 recording refuses rows without temperature.
        assert!(w.write_row("x+", 0.0, &[1.0; 3], &[0.0; 3]).is_err());
        for k in 0..10 {
            let t = 10.0 + k as f64;
            w.write_row_with_temperature("x+", k as f64 * 0.01, &[2.0 + 1e-3 * t; 3], &[0.0; 3], t)
                .unwrap();
        }
        w.write_row_with_temperature("x-", 0.2, &[1.0; 3], &[0.0; 3], f64::NAN)
            .unwrap();
        w.write_row_with_temperature("x-", 0.3, &[1.0; 3], &[0.0; 3], 20.0)
            .unwrap();
        w.finish().unwrap();
        let s = read_session(dir.path(), &ReadOptions { quiet: true }).unwrap();
        let th = s.stats[0].thermal.as_ref().unwrap();
        assert_eq!((th.count, th.min_c, th.max_c), (10, 10.0, 19.0));
        assert!((th.mean_c() - 14.5).abs() < 1e-12);
        // The row with a NaN temperature (a driver without a reading) is kept for the means and
        // left out of the temperature moments.
        assert_eq!((s.stats[1].count, s.stats[1].rejected_rows), (2, 0));
        let th = s.stats[1].thermal.as_ref().unwrap();
        assert_eq!((th.count, th.min_c, th.max_c), (1, 20.0, 20.0));

        // The same samples under a version 1 plan: the header names the fix.
        let v1 = PLAN_V2
            .replace("format_version = 3", "")
            .replace("temp_c = 10", "");
        std::fs::write(dir.path().join("plan.toml"), v1).unwrap();
        let e = read_session(dir.path(), &ReadOptions { quiet: true })
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("column 9") && e.contains("format_version = 3"),
            "{e}"
        );
    }
}

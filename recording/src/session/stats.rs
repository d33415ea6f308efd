//! Sufficient statistics of one segment's samples: everything the estimator needs, so that a session
//! of 10⁷ rows is reduced in one streaming pass and never held in memory.
//!
//! The model of a segment's mean output is linear in the means of `ω̇` and of `ω ωᵀ`
//! (`E[W] = [E ω̇ ×] + E[ω ωᵀ] − tr(E[ω ωᵀ]) I`, paper eq. 11), so those are kept, with the outputs'
//! mean and covariance (their noise level gives each segment's weight and the χ² check).
//! Sums are shifted by the segment's first sample, which keeps them exact over long segments.

use super::thermal::{ThermalAccumulator, ThermalStats};

/// Statistics of one segment.
#[derive(Clone, Debug, PartialEq)]
pub struct SegmentStats {
    /// Segment name (as in the plan).
    pub name: String,
    /// Rows used.
    pub count: u64,
    /// Rows left out because a value was NaN or infinite.
    pub rejected_rows: u64,
    /// First and last time stamps, s.
    pub t_first_s: f64,
    /// See `t_first_s`.
    pub t_last_s: f64,
    /// Mean accelerometer outputs, sensor axes, output unit.
    pub mean_u: [f64; 3],
    /// Sample covariance of the outputs, output unit².
    pub cov_u: [[f64; 3]; 3],
    /// Smallest and largest output per axis (saturation check).
    pub min_u: [f64; 3],
    /// See `min_u`.
    pub max_u: [f64; 3],
    /// Mean gyro rate, body axes, rad/s.
    pub mean_w_rad_s: [f64; 3],
    /// Mean of `ω ωᵀ`, (rad/s)².
    pub mean_wwt: [[f64; 3]; 3],
    /// Sample covariance of the gyro rate, (rad/s)².
    pub cov_w: [[f64; 3]; 3],
    /// Least-squares slope of ω against time: the segment's mean angular acceleration, rad/s².
    pub wdot_rad_s2: [f64; 3],
    /// Temperature moments (docs/model.md §9), when the recording has a `temp_c` column.
    pub thermal: Option<ThermalStats>,
}

impl SegmentStats {
    /// Standard deviation of each output, output unit.
    pub fn std_u(&self) -> [f64; 3] {
        std::array::from_fn(|i| self.cov_u[i][i].max(0.0).sqrt())
    }

    /// Standard deviation of each gyro axis, rad/s.
    pub fn std_w(&self) -> [f64; 3] {
        std::array::from_fn(|i| self.cov_w[i][i].max(0.0).sqrt())
    }

    /// Duration covered, s.
    pub fn duration_s(&self) -> f64 {
        self.t_last_s - self.t_first_s
    }
}

/// Streaming accumulator for [`SegmentStats`].
#[derive(Clone, Debug)]
pub struct SegmentAccumulator {
    name: String,
    n: u64,
    rejected: u64,
    t0: f64,
    t_last: f64,
    u0: [f64; 3],
    w0: [f64; 3],
    su: [f64; 3],
    suu: [[f64; 3]; 3],
    sw: [f64; 3],
    sww: [[f64; 3]; 3],
    st: f64,
    stt: f64,
    stw: [f64; 3],
    min_u: [f64; 3],
    max_u: [f64; 3],
    thermal: Option<ThermalAccumulator>,
}

impl SegmentAccumulator {
    /// An empty accumulator for segment `name`.
    pub fn new(name: impl Into<String>) -> Self {
        SegmentAccumulator {
            name: name.into(),
            n: 0,
            rejected: 0,
            t0: 0.0,
            t_last: 0.0,
            u0: [0.0; 3],
            w0: [0.0; 3],
            su: [0.0; 3],
            suu: [[0.0; 3]; 3],
            sw: [0.0; 3],
            sww: [[0.0; 3]; 3],
            st: 0.0,
            stt: 0.0,
            stw: [0.0; 3],
            min_u: [f64::INFINITY; 3],
            max_u: [f64::NEG_INFINITY; 3],
            thermal: None,
        }
    }

    /// Segment name.
    pub fn name(&self) -> &str {
        &self.name
    }

    /// Rows accepted so far.
    pub fn count(&self) -> u64 {
        self.n
    }

    /// Adds one row. Rows with a non-finite value are counted as rejected and left out.
    #[inline]
    pub fn push(&mut self, t_s: f64, u: &[f64; 3], w_rad_s: &[f64; 3]) {
        if !(t_s.is_finite() && u.iter().chain(w_rad_s).all(|v| v.is_finite())) {
            self.rejected += 1;
            return;
        }
        if self.n == 0 {
            self.t0 = t_s;
            self.u0 = *u;
            self.w0 = *w_rad_s;
        }
        self.n += 1;
        self.t_last = t_s;
        let t = t_s - self.t0;
        let du: [f64; 3] = std::array::from_fn(|i| u[i] - self.u0[i]);
        let dw: [f64; 3] = std::array::from_fn(|i| w_rad_s[i] - self.w0[i]);
        self.st += t;
        self.stt += t * t;
        for i in 0..3 {
            self.su[i] += du[i];
            self.sw[i] += dw[i];
            self.stw[i] += t * dw[i];
            self.min_u[i] = self.min_u[i].min(u[i]);
            self.max_u[i] = self.max_u[i].max(u[i]);
            for j in i..3 {
                self.suu[i][j] += du[i] * du[j];
                self.sww[i][j] += dw[i] * dw[j];
            }
        }
    }

    /// Adds one row with the unit's temperature, °C. A row whose temperature is NaN or infinite (a
    /// driver without a reading) is kept for the means and left out of the temperature moments,
    /// which keep their own sums of the outputs over the rows that have a reading.
    #[inline]
    pub fn push_with_temperature(
        &mut self,
        t_s: f64,
        u: &[f64; 3],
        w_rad_s: &[f64; 3],
        temp_c: f64,
    ) {
        let before = self.n;
        self.push(t_s, u, w_rad_s);
        if self.n > before && temp_c.is_finite() {
            self.thermal
                .get_or_insert_with(Default::default)
                .push(u, temp_c);
        }
    }

    /// The statistics, or `None` when no row was accepted.
    pub fn finish(&self) -> Option<SegmentStats> {
        if self.n == 0 {
            return None;
        }
        let n = self.n as f64;
        let mean_du: [f64; 3] = std::array::from_fn(|i| self.su[i] / n);
        let mean_dw: [f64; 3] = std::array::from_fn(|i| self.sw[i] / n);
        let sym = |m: &[[f64; 3]; 3], i: usize, j: usize| if i <= j { m[i][j] } else { m[j][i] };
        let denom = (n - 1.0).max(1.0);
        let cov_u = std::array::from_fn(|i| {
            std::array::from_fn(|j| (sym(&self.suu, i, j) - n * mean_du[i] * mean_du[j]) / denom)
        });
        let cov_w: [[f64; 3]; 3] = std::array::from_fn(|i| {
            std::array::from_fn(|j| (sym(&self.sww, i, j) - n * mean_dw[i] * mean_dw[j]) / denom)
        });
        let mean_w: [f64; 3] = std::array::from_fn(|i| self.w0[i] + mean_dw[i]);
        // E[ωωᵀ] = E[(w0+dw)(w0+dw)ᵀ] from the shifted sums.
        let mean_wwt = std::array::from_fn(|i| {
            std::array::from_fn(|j| {
                sym(&self.sww, i, j) / n
                    + self.w0[i] * mean_dw[j]
                    + mean_dw[i] * self.w0[j]
                    + self.w0[i] * self.w0[j]
            })
        });
        let mean_t = self.st / n;
        let var_t = self.stt / n - mean_t * mean_t;
        let wdot = std::array::from_fn(|i| {
            if var_t > 0.0 {
                (self.stw[i] / n - mean_t * mean_dw[i]) / var_t
            } else {
                0.0
            }
        });
        Some(SegmentStats {
            name: self.name.clone(),
            count: self.n,
            rejected_rows: self.rejected,
            t_first_s: self.t0,
            t_last_s: self.t_last,
            mean_u: std::array::from_fn(|i| self.u0[i] + mean_du[i]),
            cov_u,
            min_u: self.min_u,
            max_u: self.max_u,
            mean_w_rad_s: mean_w,
            mean_wwt,
            cov_w,
            wdot_rad_s2: wdot,
            thermal: self.thermal.as_ref().and_then(ThermalAccumulator::finish),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn matches_two_pass_statistics() {
        let mut acc = SegmentAccumulator::new("s");
        let rows: Vec<(f64, [f64; 3], [f64; 3])> = (0..1000)
            .map(|k| {
                let t = 10.0 + k as f64 * 1e-3;
                let x = (k as f64 * 0.37).sin();
                (
                    t,
                    [2.4 + 1e-3 * x, 2.38 - 2e-3 * x * x, 2.43],
                    [1.0 + 0.5 * t, 0.1 * x, -0.2],
                )
            })
            .collect();
        for (t, u, w) in &rows {
            acc.push(*t, u, w);
        }
        acc.push(f64::NAN, &[0.0; 3], &[0.0; 3]);
        let s = acc.finish().unwrap();
        assert_eq!((s.count, s.rejected_rows), (1000, 1));
        let n = rows.len() as f64;
        for i in 0..3 {
            let m: f64 = rows.iter().map(|r| r.1[i]).sum::<f64>() / n;
            assert!((s.mean_u[i] - m).abs() < 1e-12);
            for j in 0..3 {
                let mj: f64 = rows.iter().map(|r| r.1[j]).sum::<f64>() / n;
                let c: f64 = rows
                    .iter()
                    .map(|r| (r.1[i] - m) * (r.1[j] - mj))
                    .sum::<f64>()
                    / (n - 1.0);
                assert!((s.cov_u[i][j] - c).abs() < 1e-15);
                let wwt: f64 = rows.iter().map(|r| r.2[i] * r.2[j]).sum::<f64>() / n;
                assert!((s.mean_wwt[i][j] - wwt).abs() < 1e-9);
            }
        }
        // ω_x = 1 + 0.5 t exactly: slope 0.5 rad/s².
        assert!((s.wdot_rad_s2[0] - 0.5).abs() < 1e-9);
        assert!(s.wdot_rad_s2[2].abs() < 1e-12);
        assert!(SegmentAccumulator::new("empty").finish().is_none());
    }
}

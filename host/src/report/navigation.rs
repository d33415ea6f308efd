//! The navigation check of the paper (Figures 6/7 and 9/10): integrate the specific-force error of a
//! run twice and see how far a navigator would drift.
//!
//! As in the paper's ground experiment, the integration is done in body axes with the plan's known
//! attitude: on a table spinning about the vertical, gravity is constant in body axes (`g·up_b`), and
//! so is the true specific force at the reference point, so `a = f − g·up_b` is the acceleration error
//! a strap-down navigator would integrate before attitude rotation. This is the error budget the paper
//! plots; a full mechanisation would additionally rotate the across-axis part of the error and average it
//! out over each turn, which hides exactly the lever-arm error this check is meant to show.

/// Velocity and position error of one run, sampled at the integration steps.
#[derive(Clone, Debug, PartialEq)]
pub struct Drift {
    /// Time since the start of the run, s.
    pub t_s: Vec<f64>,
    /// Velocity error, body axes, m/s.
    pub velocity_m_s: Vec<[f64; 3]>,
    /// Position error, body axes, m.
    pub position_m: Vec<[f64; 3]>,
}

impl Drift {
    /// Norm of the final position error, m.
    pub fn final_position_error_m(&self) -> f64 {
        self.position_m.last().map_or(0.0, norm)
    }

    /// Norm of the final velocity error, m/s.
    pub fn final_velocity_error_m_s(&self) -> f64 {
        self.velocity_m_s.last().map_or(0.0, norm)
    }
}

fn norm(v: &[f64; 3]) -> f64 {
    (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt()
}

/// Integrates `(t, f)` samples (f: specific force at the reference point, body axes, m/s²) minus the
/// true specific force `g·up_b`, with the trapezoidal rule, starting at rest.
pub fn integrate_drift(
    samples: impl IntoIterator<Item = (f64, [f64; 3])>,
    true_f_m_s2: [f64; 3],
) -> Drift {
    let mut d = Drift {
        t_s: Vec::new(),
        velocity_m_s: Vec::new(),
        position_m: Vec::new(),
    };
    let mut prev: Option<(f64, [f64; 3])> = None;
    let mut v = [0.0; 3];
    let mut p = [0.0; 3];
    let mut t0 = 0.0;
    for (t, f) in samples {
        let a: [f64; 3] = std::array::from_fn(|j| f[j] - true_f_m_s2[j]);
        match prev {
            None => t0 = t,
            Some((tp, ap)) => {
                let dt = t - tp;
                for j in 0..3 {
                    let v_new = v[j] + 0.5 * (a[j] + ap[j]) * dt;
                    p[j] += 0.5 * (v[j] + v_new) * dt;
                    v[j] = v_new;
                }
            }
        }
        d.t_s.push(t - t0);
        d.velocity_m_s.push(v);
        d.position_m.push(p);
        prev = Some((t, a));
    }
    d
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn constant_error_drifts_as_half_a_t_squared() {
        // A 1 mg error for 60 s: v = a t = 0.588 m/s, p = a t²/2 = 17.65 m (hand-derived).
        let a = 1e-3 * 9.80665;
        let samples = (0..=6000).map(|k| (k as f64 * 0.01, [a, 0.0, 9.80665]));
        let d = integrate_drift(samples, [0.0, 0.0, 9.80665]);
        assert!((d.final_velocity_error_m_s() - a * 60.0).abs() < 1e-9);
        assert!((d.final_position_error_m() - 0.5 * a * 3600.0).abs() < 1e-6);
        assert_eq!(d.t_s.len(), 6001);
    }
}

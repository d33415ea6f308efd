//! The temperature fit (docs/model.md §9): zero biases and scale factors as polynomials in
//! `ΔT = T − T_ref`, the misalignment constant, from the static segments of a session recorded at
//! several temperatures (a chamber's soak steps, slow ramps at rest, or both).
//!
//! Each accelerometer `i` is fitted on its own, because with a constant misalignment the model of
//! output `i` involves only row `i` of `M`:
//!
//! ```text
//! U_i = (1 + S_i(ΔT))·m_i·f + u0_i + P_i(ΔT),   S_i, P_i polynomials without constant term
//! ```
//!
//! It is fitted by Gauss–Newton over every sample at once through the segments' temperature moments
//! ([`recording::session::thermal`]), with the degrees of `P_i` and `S_i` (0..=3 each) chosen by the
//! Bayesian information criterion, the χ² first divided by the largest model's χ²/dof when that
//! exceeds 1 (noise the segments' own scatter does not show would otherwise buy higher degrees).
//! The result then refers every segment's statistics to `T_ref`, and the usual estimator runs on
//! them unchanged: its biases, scale factors and angles are the values at `T_ref`.
//!
//! Only attitudes seen over a temperature span determine the terms (`determining`): a session that
//! spans temperature only between attitudes, such as a hand-held one warming up, gets no model.
//!
//! The gyro bias gets its polynomial from the static segments (`thermal_gyro`), and
//! the misalignment held constant is tested across the soak temperatures
//! (`thermal_misalignment`): a significant change is a warning, not a model term.

use super::note::Note;
use super::solve::invert_spd;
use nalgebra::{DMatrix, DVector};
use recording::session::thermal::{binomial, ThermalStats, ORIGIN_C, SCALE_C, TERMS};
use recording::session::{Plan, SegmentPlan, SegmentStats};
use shared::sensor_models::{TemperatureModel, MAX_TEMPERATURE_DEGREE as DEG};

/// Smallest temperature span of the static segments for a temperature model, °C.
pub(crate) const MIN_SPAN_C: f64 = 5.0;
/// The reference temperature when the data cover it, °C.
pub(crate) const PREFERRED_REFERENCE_C: f64 = 25.0;
/// Segments whose temperature moves less than this are treated as soaks: their own scatter is noise.
const SOAK_SPAN_C: f64 = 1.0;
/// Parameters per axis: `m_i` (3), `u0_i`, `p_1..p_3`, `s_1..s_3`.
const NPAR: usize = 4 + 2 * DEG;
const GAUSS_NEWTON_STEPS: usize = 8;

/// One segment's residual after the fit, like a soak step's row of a table.
#[derive(Clone, Debug, PartialEq)]
pub struct ThermalStep {
    /// Segment name.
    pub segment: String,
    /// Mean temperature, °C.
    pub mean_c: f64,
    /// Mean residual per output (data − model), output unit.
    pub residual_out: [f64; 3],
    /// 1σ of that mean from the segment's noise, output unit.
    pub sigma_out: [f64; 3],
}

/// The temperature fit's result.
#[derive(Clone, Debug, PartialEq)]
pub struct ThermalFit {
    /// The model to apply (docs/model.md §9).
    pub model: TemperatureModel,
    /// The zero biases at `T_ref` this fit found, output unit (the main estimate's agree to noise).
    pub zero_bias_ref_out: [f64; 3],
    /// The degree of each `P_i` the data chose.
    pub zero_bias_degree: [usize; 3],
    /// The degree of each `S_i` the data chose.
    pub scale_degree: [usize; 3],
    /// 1σ of `model.zero_bias_out_per_c` (0 where the degree leaves a coefficient out).
    pub zero_bias_sigma: [[f64; DEG]; 3],
    /// 1σ of `model.scale_rel_per_c`.
    pub scale_sigma: [[f64; DEG]; 3],
    /// Covariance of each axis's zero-bias coefficients (for the 1σ band of `P_i(T)`).
    pub zero_bias_cov: [[[f64; DEG]; DEG]; 3],
    /// Covariance of each axis's scale coefficients.
    pub scale_cov: [[[f64; DEG]; DEG]; 3],
    /// χ², degrees of freedom, per axis, of the chosen model.
    pub chi2: [(f64, usize); 3],
    /// Residuals per static segment.
    pub steps: Vec<ThermalStep>,
    /// The degree of each gyro axis's bias polynomial the data chose; `None` when the recording has
    /// no gyro readings.
    pub gyro_bias_degree: Option<[usize; 3]>,
    /// 1σ of `model.gyro_bias_rad_s_per_c` (0 where the degree leaves a coefficient out).
    pub gyro_bias_sigma: [[f64; DEG]; 3],
    /// The gyro bias at `T_ref` from the rests and its 1σ, rad/s; `None` when the recording has no
    /// gyro readings. It is the calibration's gyro bias when the session has no spins to fit the
    /// whole gyro from (docs/model.md §8, §9).
    pub gyro_bias_ref_rad_s: Option<([f64; 3], [f64; 3])>,
    /// How each degree was chosen, for the report.
    pub notes: Vec<Note>,
}

/// A static segment as the fit sees it.
struct Obs<'a> {
    name: &'a str,
    up_b: [f64; 3],
    ts: &'a ThermalStats,
    /// Per-sample noise variance per output, output unit².
    var: [f64; 3],
}

/// Why a temperature model could not be fitted where the session has the temperatures for one.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ThermalError {
    /// An axis's bias and scale are not determined by the segments kept.
    #[error(
        "accelerometer {axis}: the static segments do not determine its bias and scale (too few \
         attitudes)"
    )]
    Undetermined {
        /// The axis, `x`, `y` or `z`.
        axis: &'static str,
    },
    /// No pair of degrees could be fitted.
    #[error("no temperature model can be fitted")]
    NoModel,
    /// The fitted model is not one the device can use (`shared`'s error has no `std` source).
    #[error("{0}")]
    Implausible(shared::sensor_models::TemperatureModelError),
}

/// Fits the temperature model when the session determines it: static segments of a known attitude
/// seen over at least [`MIN_SPAN_C`] (`determining`, docs/model.md §9); `Ok(None)` otherwise, with a
/// note naming the numbers when temperatures were recorded at all.
pub(crate) fn fit_session(
    plan: &Plan,
    stats: &[SegmentStats],
) -> Result<(Option<ThermalFit>, Vec<Note>), ThermalError> {
    fit_with(plan, stats, None)
}

/// `fit_session` at given degrees `(zero bias, scale)` per axis instead of the BIC's choice: on
/// noise-free statistics its 1σ are the Cramér–Rao bound of a plan (the prediction `host plan` checks a plan with).
pub(crate) fn fit_session_at_degrees(
    plan: &Plan,
    stats: &[SegmentStats],
    degrees: [(usize, usize); 3],
) -> Result<(Option<ThermalFit>, Vec<Note>), ThermalError> {
    fit_with(plan, stats, Some(degrees))
}

fn fit_with(
    plan: &Plan,
    stats: &[SegmentStats],
    degrees: Option<[(usize, usize); 3]>,
) -> Result<(Option<ThermalFit>, Vec<Note>), ThermalError> {
    let statics: Vec<(Obs, &SegmentPlan)> = stats
        .iter()
        .filter_map(|st| {
            let seg = plan.segment(&st.name)?;
            let ts = st.thermal.as_ref()?;
            seg.is_static().then(|| {
                let o = Obs {
                    name: &st.name,
                    up_b: seg.up_b,
                    ts,
                    var: noise_variance(st, ts),
                };
                (o, seg)
            })
        })
        .collect();
    if statics.is_empty() {
        return Ok((None, Vec::new()));
    }
    let (lo, hi) = span(statics.iter().map(|(o, _)| o));
    if hi - lo < MIN_SPAN_C {
        return Ok((None, vec![Note::ThermalSpanShort { lo, hi }]));
    }
    let obs = match determining(statics, (lo, hi)) {
        Ok(obs) => obs,
        Err(refusal) => return Ok((None, vec![refusal])),
    };
    let (lo, hi) = span(obs.iter());
    let reference_c = PREFERRED_REFERENCE_C.clamp(lo, hi);
    let mut fit = ThermalFit::empty(reference_c, [lo, hi], &obs);
    for axis in 0..3 {
        fit_axis(&obs, axis, degrees.map(|d| d[axis]), &mut fit)?;
    }
    let statics: Vec<(&SegmentStats, &ThermalStats, [f64; 3])> = stats
        .iter()
        .filter_map(|st| {
            let seg = plan.segment(&st.name)?;
            let ts = st.thermal.as_ref()?;
            seg.is_static().then_some((st, ts, seg.up_b))
        })
        .collect();
    let pairs: Vec<(&SegmentStats, &ThermalStats)> =
        statics.iter().map(|(st, ts, _)| (*st, *ts)).collect();
    if let Some(g) = super::thermal_gyro::fit(&pairs, reference_c) {
        // Degree 0 everywhere: the data show no dependence, and the model carries none.
        fit.model.gyro_bias_rad_s_per_c = g.degree.iter().any(|&d| d > 0).then_some(g.per_c);
        fit.gyro_bias_degree = Some(g.degree);
        fit.gyro_bias_sigma = g.sigma;
        fit.gyro_bias_ref_rad_s = Some((g.bias_ref_rad_s, g.bias_ref_sigma_rad_s));
        fit.notes.extend(g.notes);
    }
    // The misalignment is compared across the soaks whose attitude determines the model.
    let soaks: Vec<_> = statics
        .into_iter()
        .filter(|(st, ts, _)| {
            ts.max_c - ts.min_c < SOAK_SPAN_C && obs.iter().any(|o| o.name == st.name)
        })
        .collect();
    let warnings = super::thermal_misalignment::check(&soaks);
    fit.model.check().map_err(ThermalError::Implausible)?;
    Ok((Some(fit), warnings))
}

/// The lowest and highest temperature the segments read, °C.
fn span<'a>(obs: impl IntoIterator<Item = &'a Obs<'a>>) -> (f64, f64) {
    obs.into_iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), o| {
            (lo.min(o.ts.min_c), hi.max(o.ts.max_c))
        })
}

/// The static segments that determine a temperature model (docs/model.md §9, "When the session
/// determines it"): those of a known attitude (not free) whose mount is seen over at least
/// [`MIN_SPAN_C`], when they hold four attitudes not in one plane (each axis's bias and scale).
/// Otherwise the warning that says why there is no model, with the session's numbers.
fn determining<'a>(
    statics: Vec<(Obs<'a>, &SegmentPlan)>,
    (lo, hi): (f64, f64),
) -> Result<Vec<Obs<'a>>, Note> {
    // Each known attitude's temperatures: (mount, lowest, highest).
    let mut mounts: Vec<(String, f64, f64)> = Vec::new();
    for (o, seg) in statics.iter().filter(|(_, seg)| !seg.is_free()) {
        let name = seg.mount_name();
        match mounts.iter_mut().find(|m| m.0 == name) {
            Some(m) => *m = (name, m.1.min(o.ts.min_c), m.2.max(o.ts.max_c)),
            None => mounts.push((name, o.ts.min_c, o.ts.max_c)),
        }
    }
    let held = |name: &str| {
        mounts
            .iter()
            .any(|m| m.0 == name && m.2 - m.1 >= MIN_SPAN_C)
    };
    let (total, free) = (
        statics.len(),
        statics.iter().filter(|(_, seg)| seg.is_free()).count(),
    );
    let kept: Vec<Obs> = statics
        .into_iter()
        .filter(|(_, seg)| !seg.is_free() && held(&seg.mount_name()))
        .map(|(o, _)| o)
        .collect();
    if !kept.is_empty() && spans_space(&kept) {
        return Ok(kept);
    }
    let attitudes = mounts.iter().filter(|m| m.2 - m.1 >= MIN_SPAN_C).count();
    let widest = mounts
        .iter()
        .max_by(|a, b| (a.2 - a.1).total_cmp(&(b.2 - b.1)))
        .map(|(name, a, b)| (b - a, name.clone()));
    Err(Note::ThermalNotDetermined {
        lo,
        hi,
        attitudes,
        free,
        total,
        widest,
    })
}

/// Whether the segments' ups hold four attitudes out of one plane: `Σ [f 1][f 1]ᵀ` of full rank.
fn spans_space(obs: &[Obs]) -> bool {
    let mut gram = nalgebra::Matrix4::<f64>::zeros();
    for o in obs {
        let x = nalgebra::Vector4::new(o.up_b[0], o.up_b[1], o.up_b[2], 1.0);
        gram += x * x.transpose();
    }
    let eig = gram.symmetric_eigenvalues();
    eig.min() > 1e-9 * eig.max().max(f64::MIN_POSITIVE)
}

/// Per-sample noise variance: a soak's own scatter, or a ramp's scatter about its own cubic.
fn noise_variance(st: &SegmentStats, ts: &ThermalStats) -> [f64; 3] {
    std::array::from_fn(|i| {
        let soak = st.cov_u[i][i].max(f64::MIN_POSITIVE);
        if ts.max_c - ts.min_c < SOAK_SPAN_C || ts.count <= 2 * TERMS as u64 {
            return soak;
        }
        let g = DMatrix::from_fn(TERMS, TERMS, |j, k| ts.gram()[j][k]);
        let b = DVector::from_fn(TERMS, |k, _| ts.sum_u_x_pow[i][k]);
        match g.cholesky() {
            Some(c) => {
                let beta = c.solve(&b);
                let rss = ts.sum_u2[i] - beta.dot(&b);
                (rss / (ts.count as f64 - TERMS as f64)).max(f64::MIN_POSITIVE)
            }
            None => soak,
        }
    })
}

/// Which of the [`NPAR`] parameters a degree pair uses.
fn active(db: usize, ds: usize) -> Vec<usize> {
    (0..4)
        .chain((0..db).map(|k| 4 + k))
        .chain((0..ds).map(|k| 4 + DEG + k))
        .collect()
}

/// `β'` (the model polynomial in `x' = (T − T_ref)/SCALE_C`) of one segment and its Jacobian.
fn model_poly(
    theta: &[f64; NPAR],
    f: &[f64; 3],
    shift: f64,
) -> ([f64; TERMS], [[f64; NPAR]; TERMS]) {
    let mf = theta[0] * f[0] + theta[1] * f[1] + theta[2] * f[2];
    let mut beta = [0.0; TERMS];
    let mut jac = [[0.0; NPAR]; TERMS];
    beta[0] = mf + theta[3] - shift;
    jac[0][..3].copy_from_slice(f);
    jac[0][3] = 1.0;
    for k in 1..TERMS {
        let (p, s) = (4 + k - 1, 4 + DEG + k - 1);
        beta[k] = theta[p] + theta[s] * mf;
        for j in 0..3 {
            jac[k][j] = theta[s] * f[j];
        }
        jac[k][p] = 1.0;
        jac[k][s] = mf;
    }
    (beta, jac)
}

/// `D` with `β = D β'`: a polynomial in `x' = x − d` re-expanded in `x`.
fn shift_matrix(reference_c: f64) -> [[f64; TERMS]; TERMS] {
    let d = (reference_c - ORIGIN_C) / SCALE_C;
    std::array::from_fn(|j| {
        std::array::from_fn(|k| {
            if k >= j {
                binomial(k, j) * (-d).powi((k - j) as i32)
            } else {
                0.0
            }
        })
    })
}

struct AxisResult {
    theta: [f64; NPAR],
    cov: DMatrix<f64>,
    chi2: f64,
    dof: i64,
    idx: Vec<usize>,
}

/// Gauss–Newton for one axis and one degree pair, from `start`.
fn solve_axis(
    obs: &[Obs],
    axis: usize,
    idx: &[usize],
    d: &[[f64; TERMS]; TERMS],
    start: [f64; NPAR],
) -> Option<AxisResult> {
    let mut theta = start;
    let rows: u64 = obs.iter().map(|o| o.ts.count).sum();
    let dof = rows as i64 - idx.len() as i64;
    for step in 0..=GAUSS_NEWTON_STEPS {
        let (n, g, chi2) = normal_equations(obs, axis, idx, d, &theta);
        let inv = invert_spd(&n, 1e-13)?;
        if step == GAUSS_NEWTON_STEPS {
            return Some(AxisResult {
                theta,
                cov: inv,
                chi2,
                dof,
                idx: idx.to_vec(),
            });
        }
        let delta = &inv * &g;
        for (a, &p) in idx.iter().enumerate() {
            theta[p] += delta[a];
        }
    }
    None
}

/// `JᵀWJ`, `JᵀW r` and χ² over all samples, from the moments.
fn normal_equations(
    obs: &[Obs],
    axis: usize,
    idx: &[usize],
    d: &[[f64; TERMS]; TERMS],
    theta: &[f64; NPAR],
) -> (DMatrix<f64>, DVector<f64>, f64) {
    let k = idx.len();
    let mut n = DMatrix::zeros(k, k);
    let mut g = DVector::zeros(k);
    let mut chi2 = 0.0;
    for o in obs {
        let (bp, jp) = model_poly(theta, &o.up_b, o.ts.u_shift[axis]);
        let beta: [f64; TERMS] = std::array::from_fn(|j| (0..TERMS).map(|m| d[j][m] * bp[m]).sum());
        let jac = DMatrix::from_fn(TERMS, k, |j, a| {
            (0..TERMS).map(|m| d[j][m] * jp[m][idx[a]]).sum()
        });
        let gram = DMatrix::from_fn(TERMS, TERMS, |j, m| o.ts.gram()[j][m]);
        let b = DVector::from_fn(TERMS, |j, _| o.ts.sum_u_x_pow[axis][j]);
        let r = b - &gram * DVector::from_row_slice(&beta);
        let w = 1.0 / o.var[axis];
        n += jac.transpose() * &gram * &jac * w;
        g += jac.transpose() * r * w;
        chi2 += o.ts.residual_sum_squares(axis, &beta) * w;
    }
    (n, g, chi2)
}

/// Fits axis `axis` at every degree pair (or only at `forced`), starting from the fit without
/// temperature terms, keeps the pair of least BIC and writes it into `fit`.
fn fit_axis(
    obs: &[Obs],
    axis: usize,
    forced: Option<(usize, usize)>,
    fit: &mut ThermalFit,
) -> Result<(), ThermalError> {
    let d = shift_matrix(fit.model.reference_c);
    let base = solve_axis(obs, axis, &active(0, 0), &d, [0.0; NPAR]).ok_or(
        ThermalError::Undetermined {
            axis: shared::params::axis_name(axis),
        },
    )?;
    let rows: u64 = obs.iter().map(|o| o.ts.count).sum();
    let mut results = Vec::new();
    for db in 0..=DEG {
        for ds in 0..=DEG {
            if forced.is_some_and(|f| f != (db, ds)) {
                continue;
            }
            if let Some(r) = solve_axis(obs, axis, &active(db, ds), &d, base.theta) {
                results.push(((db, ds), r));
            }
        }
    }
    let largest = results
        .iter()
        .max_by_key(|((db, ds), _)| db + ds)
        .map(|(_, r)| (r.chi2 / r.dof.max(1) as f64).max(1.0))
        .unwrap_or(1.0);
    let bic = |r: &AxisResult| r.chi2 / largest + r.idx.len() as f64 * (rows as f64).ln();
    let ((db, ds), best) = results
        .into_iter()
        .min_by(|a, b| bic(&a.1).total_cmp(&bic(&b.1)))
        .ok_or(ThermalError::NoModel)?;
    let scale2 = (best.chi2 / best.dof.max(1) as f64).max(1.0);
    fit.notes.push(Note::ThermalAccDegrees {
        axis,
        zero_bias_degree: db,
        scale_degree: ds,
        chi2_per_dof: best.chi2 / best.dof.max(1) as f64,
        scaled: scale2 > 1.0,
    });
    fit.zero_bias_degree[axis] = db;
    fit.scale_degree[axis] = ds;
    fit.zero_bias_ref_out[axis] = best.theta[3];
    fit.chi2[axis] = (best.chi2, best.dof.max(0) as usize);
    for k in 0..DEG {
        let per_c = SCALE_C.powi(k as i32 + 1);
        let sd = |p: usize| {
            best.idx
                .iter()
                .position(|&q| q == p)
                .map_or(0.0, |a| (best.cov[(a, a)] * scale2).sqrt() / per_c)
        };
        fit.model.zero_bias_out_per_c[axis][k] = best.theta[4 + k] / per_c;
        fit.model.scale_rel_per_c[axis][k] = best.theta[4 + DEG + k] / per_c;
        fit.zero_bias_sigma[axis][k] = sd(4 + k);
        fit.scale_sigma[axis][k] = sd(4 + DEG + k);
    }
    let pos = |p: usize| best.idx.iter().position(|&q| q == p);
    for a in 0..DEG {
        for b in 0..DEG {
            let per_c = SCALE_C.powi(a as i32 + 1) * SCALE_C.powi(b as i32 + 1);
            let c = |first: usize| match (pos(first + a), pos(first + b)) {
                (Some(i), Some(j)) => best.cov[(i, j)] * scale2 / per_c,
                _ => 0.0,
            };
            fit.zero_bias_cov[axis][a][b] = c(4);
            fit.scale_cov[axis][a][b] = c(4 + DEG);
        }
    }
    for (o, step) in obs.iter().zip(&mut fit.steps) {
        let (bp, _) = model_poly(&best.theta, &o.up_b, o.ts.u_shift[axis]);
        let beta: [f64; TERMS] = std::array::from_fn(|j| (0..TERMS).map(|m| d[j][m] * bp[m]).sum());
        let n = o.ts.count as f64;
        let predicted: f64 = (0..TERMS).map(|j| beta[j] * o.ts.sum_x_pow[j]).sum::<f64>() / n;
        step.residual_out[axis] = o.ts.sum_u_x_pow[axis][0] / n - predicted;
        step.sigma_out[axis] = (o.var[axis] / n).sqrt();
    }
    Ok(())
}

impl ThermalFit {
    /// No temperature terms yet: the fit over `valid_range_c` about `reference_c`, one step a segment.
    fn empty(reference_c: f64, valid_range_c: [f64; 2], obs: &[Obs]) -> ThermalFit {
        ThermalFit {
            model: TemperatureModel {
                reference_c,
                valid_range_c,
                zero_bias_out_per_c: [[0.0; DEG]; 3],
                scale_rel_per_c: [[0.0; DEG]; 3],
                gyro_bias_rad_s_per_c: None,
            },
            zero_bias_ref_out: [0.0; 3],
            zero_bias_degree: [0; 3],
            scale_degree: [0; 3],
            zero_bias_sigma: [[0.0; DEG]; 3],
            scale_sigma: [[0.0; DEG]; 3],
            zero_bias_cov: [[[0.0; DEG]; DEG]; 3],
            scale_cov: [[[0.0; DEG]; DEG]; 3],
            chi2: [(0.0, 0); 3],
            steps: obs
                .iter()
                .map(|o| ThermalStep {
                    segment: o.name.to_string(),
                    mean_c: o.ts.mean_c(),
                    residual_out: [0.0; 3],
                    sigma_out: [0.0; 3],
                })
                .collect(),
            gyro_bias_degree: None,
            gyro_bias_sigma: [[0.0; DEG]; 3],
            gyro_bias_ref_rad_s: None,
            notes: Vec::new(),
        }
    }

    /// Each accelerometer's χ²/dof of its chosen model over every sample (NaN without degrees of
    /// freedom). A segment enters the main fit only by its mean referred to `T_ref`, so a misfit
    /// within a ramp (its shape against temperature, the mean unchanged) shows here and not in the
    /// main fit's χ²/dof: the verdict checks both (docs/model.md §9).
    pub fn reduced_chi2(&self) -> [f64; 3] {
        self.chi2
            .map(|(c, dof)| if dof > 0 { c / dof as f64 } else { f64::NAN })
    }

    /// The largest of [`ThermalFit::reduced_chi2`] (NaN when any is): the figure the verdict checks.
    pub fn worst_reduced_chi2(&self) -> f64 {
        self.reduced_chi2()
            .into_iter()
            .fold(f64::NEG_INFINITY, |a, b| {
                if a.is_nan() || b.is_nan() {
                    f64::NAN
                } else {
                    a.max(b)
                }
            })
    }

    /// `c1·ΔT + c2·ΔT² + c3·ΔT³` of axis `axis` at `temp_c` and its 1σ from `cov`.
    pub fn curve(&self, c: &[f64; DEG], cov: &[[f64; DEG]; DEG], temp_c: f64) -> (f64, f64) {
        let dt = temp_c - self.model.reference_c;
        let g = [dt, dt * dt, dt * dt * dt];
        let value = (0..DEG).map(|k| c[k] * g[k]).sum();
        let var: f64 = (0..DEG)
            .flat_map(|a| (0..DEG).map(move |b| (a, b)))
            .map(|(a, b)| g[a] * cov[a][b] * g[b])
            .sum();
        (value, var.max(0.0).sqrt())
    }

    /// The statistics referred to `T_ref`: each segment's mean outputs with the model's bias change
    /// removed and its scale change divided out (exact at rest, where `m_i·f` is constant:
    /// `E[U] = (1 + E[S])·m·f + u0 + E[P]`).
    pub(crate) fn refer_to_reference(&self, stats: &[SegmentStats]) -> Vec<SegmentStats> {
        let m = &self.model;
        stats
            .iter()
            .map(|st| {
                let Some(ts) = &st.thermal else {
                    return st.clone();
                };
                let ex = ts.mean_powers_about(m.reference_c);
                let mean_poly = |c: &[f64; DEG]| {
                    (0..DEG)
                        .map(|k| c[k] * SCALE_C.powi(k as i32 + 1) * ex[k + 1])
                        .sum::<f64>()
                };
                let mut out = st.clone();
                let var = noise_variance(st, ts);
                let ramp = ts.max_c - ts.min_c >= SOAK_SPAN_C;
                let gain: [f64; 3] =
                    std::array::from_fn(|i| 1.0 + mean_poly(&m.scale_rel_per_c[i]));
                if let Some(b) = &m.gyro_bias_rad_s_per_c {
                    // At rest the mean rate is the bias: remove its mean change over the segment
                    // (`E[ωωᵀ]` shifts with it; the scatter is the drift the model explains).
                    let d: [f64; 3] = std::array::from_fn(|i| mean_poly(&b[i]));
                    let w = st.mean_w_rad_s;
                    for i in 0..3 {
                        out.mean_w_rad_s[i] = w[i] - d[i];
                        for j in 0..3 {
                            out.mean_wwt[i][j] =
                                st.mean_wwt[i][j] - d[i] * w[j] - w[i] * d[j] + d[i] * d[j];
                        }
                    }
                }
                for i in 0..3 {
                    let u0 = self.zero_bias_ref_out[i];
                    let p = mean_poly(&m.zero_bias_out_per_c[i]);
                    let refer = |u: f64| u0 + (u - u0 - p) / gain[i];
                    out.mean_u[i] = refer(st.mean_u[i]);
                    out.min_u[i] = refer(st.min_u[i]);
                    out.max_u[i] = refer(st.max_u[i]);
                    for j in 0..3 {
                        // A ramp's own scatter includes the drift the model explains: use the
                        // scatter about its own cubic instead, without correlations.
                        out.cov_u[i][j] = match (ramp, i == j) {
                            (true, true) => var[i] / (gain[i] * gain[i]),
                            (true, false) => 0.0,
                            (false, _) => st.cov_u[i][j] / (gain[i] * gain[j]),
                        };
                    }
                }
                out
            })
            .collect()
    }
}

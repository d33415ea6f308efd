//! Monte Carlo of the estimator on simulated sessions with fixture errors (docs/model.md §7): the
//! errors of each calibration on held-out attitudes and held-out motion, against the simulator's
//! known truth. Two generators: the project's simulator row by row (`simulate_rows`, the full runs)
//! and the exact distribution of each segment's means (`testkit::noisy_stats`, the short runs in the
//! normal tests, same segment lengths).

use crate::estimate::attitude::{lq, rotation_vector};
use crate::estimate::{calibrate_session_stats, CalibrationOutcome, EstimateOptions};
use crate::sim::testkit::{self, TableErrors};
use crate::sim::NoiseModel;
use nalgebra::Matrix3;
use recording::session::{Plan, SegmentStats};
use shared::forward::{BodyMotion, ForwardModel};
use shared::linalg::{self, RowMajor3};
use shared::units::{BodyAngularAccel, BodyRate, BodySpecificForce};
use shared::{Calibration, FittedStatic};

/// How a session's statistics are made.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Generator {
    /// `simulate_rows` (every sample, 1 mg accelerometer and 0.05 °/s gyro white noise).
    Rows,
    /// The exact distribution of the segment means (same noise).
    Stats,
}

/// One Monte Carlo case.
#[derive(Clone, Debug)]
pub struct Case {
    /// Printed title.
    pub title: String,
    /// The plan, with the attitude prior it declares.
    pub plan: Plan,
    /// 1σ per axis of the true tilt of each mount, degrees.
    pub true_tilt_deg: f64,
    /// Seeds 0..seeds.
    pub seeds: u64,
    /// The generator.
    pub generator: Generator,
    /// Estimator options.
    pub options: EstimateOptions,
    /// Also run the norm-only method on the static segments.
    pub norm_only: bool,
    /// The simulated gyro reads `G ω + b` (b in rad/s); `None`: perfect.
    pub gyro: Option<(RowMajor3, [f64; 3])>,
    /// Draw the table's rate scale error per seed with the plan's `table_rate_sigma_ppm` (else the
    /// table's rate is exact).
    pub table_rate_error: bool,
}

/// One seed's errors.
#[derive(Clone, Debug)]
pub struct SeedResult {
    /// Worst error over 26 held-out attitudes × 3 axes, µg, as is.
    pub static_raw_ug: f64,
    /// The same after removing the best common rotation.
    pub static_ug: f64,
    /// RMS over the held-out attitudes after the best common rotation, µg.
    pub static_rms_ug: f64,
    /// RMS error at |ω| = 200 °/s (random axis and ω̇), after the common rotation, µg.
    pub dyn200_ug: f64,
    /// RMS error for |ω| uniform to 300 °/s (random axis and ω̇), after the common rotation, µg.
    pub dyn300_ug: f64,
    /// Lever-arm errors, m.
    pub lever_err_m: RowMajor3,
    /// Body-frame alignment error (rotation of the fitted frame), rad.
    pub body_err_rad: [f64; 3],
    /// Its reported 1σ, rad.
    pub body_sigma_rad: [f64; 3],
    /// The report warned of a mount tilted beyond 3× its prior.
    pub tilt_warning: bool,
    /// The norm-only method's static error after its best rotation (worst, rms), µg.
    pub norm_only_static_ug: Option<(f64, f64)>,
    /// The gyro estimate's errors and reported 1σ.
    pub gyro_err: Option<GyroErrors>,
    /// `G` − `G_true` after removing the body frame's common rotation (the gyro relative to the
    /// accelerometer triad).
    pub gyro_err_rotated: Option<RowMajor3>,
}

/// A gyro estimate's errors and reported 1σ: (G − G_true, b − b_true, σ_G, σ_b).
pub type GyroErrors = (RowMajor3, [f64; 3], RowMajor3, [f64; 3]);

/// All seeds of a case.
pub struct CaseResult {
    /// The case's title.
    pub title: String,
    /// Per seed.
    pub seeds: Vec<SeedResult>,
}

/// A uniformly random unit vector.
fn unit(rng: &mut shared::rng::Rng) -> [f64; 3] {
    rng.unit_vector()
}

/// The rotation `R` minimising Σ |R a_k − b_k|² (Kabsch).
fn best_rotation(a: &[[f64; 3]], b: &[[f64; 3]]) -> Matrix3<f64> {
    crate::estimate::attitude::best_rotation(a, b).expect("an SVD of a 3×3 matrix")
}

fn apply(r: &Matrix3<f64>, v: &[f64; 3]) -> [f64; 3] {
    let x = r * nalgebra::Vector3::from_column_slice(v);
    [x[0], x[1], x[2]]
}

/// Compensated specific force (g) of outputs `u` with a static estimate and lever arms.
fn compensate(
    fitted: &FittedStatic,
    r: &RowMajor3,
    g: f64,
    u: &[f64; 3],
    m: &BodyMotion,
) -> [f64; 3] {
    let minv = linalg::inverse(&fitted.m_out_per_g).expect("invertible");
    let w = linalg::lever_matrix(&m.omega.rad_s, &m.omega_dot.rad_s2);
    let du: [f64; 3] = core::array::from_fn(|i| {
        let lever = linalg::dot(&fitted.m_out_per_g[i], &linalg::mat_vec(&w, &r[i])) / g;
        u[i] - fitted.zero_bias_out[i] - lever
    });
    linalg::mat_vec(&minv, &du)
}

/// Static errors on 26 random held-out attitudes, µg.
pub struct StaticErrors {
    /// Worst as is.
    pub raw_worst_ug: f64,
    /// Worst after the best common rotation.
    pub worst_ug: f64,
    /// RMS after the best common rotation.
    pub rms_ug: f64,
    /// The rotation.
    pub rotation: Matrix3<f64>,
}

/// Static errors on 26 random held-out attitudes.
pub fn static_errors(
    truth: &Calibration,
    fitted: &FittedStatic,
    rng: &mut shared::rng::Rng,
) -> StaticErrors {
    let unit_model = ForwardModel::new(truth).expect("valid truth");
    let g = truth.gravity_m_s2;
    let ups: Vec<[f64; 3]> = (0..26).map(|_| unit(rng)).collect();
    let est: Vec<[f64; 3]> = ups
        .iter()
        .map(|up| {
            let m = shared::forward::TableState::at_rest(*up).motion(g);
            compensate(fitted, &[[0.0; 3]; 3], g, &unit_model.outputs(&m).raw, &m)
        })
        .collect();
    let worst = |rot: &Matrix3<f64>| {
        est.iter()
            .zip(&ups)
            .flat_map(|(f, up)| {
                let f = apply(rot, f);
                (0..3).map(move |i| (f[i] - up[i]).abs() * 1e6)
            })
            .fold(0.0, f64::max)
    };
    let rot = best_rotation(&est, &ups);
    let rms_ug = rms(est.iter().zip(&ups).flat_map(|(f, up)| {
        let f = apply(&rot, f);
        (0..3).map(move |i| (f[i] - up[i]) * 1e6)
    }));
    StaticErrors {
        raw_worst_ug: worst(&Matrix3::identity()),
        worst_ug: worst(&rot),
        rms_ug,
        rotation: rot,
    }
}

/// RMS dynamic error (µg) over 60 held-out motions: random up, ω along a random axis with magnitude
/// `rate_deg_s(rng)`, ω̇ random to 50 rad/s²; the estimate's output rotated by `rot`.
fn dynamic_error(
    truth: &Calibration,
    out: &CalibrationOutcome,
    gyro: Option<&(RowMajor3, [f64; 3])>,
    rot: &Matrix3<f64>,
    rng: &mut shared::rng::Rng,
    rate_deg_s: &dyn Fn(&mut shared::rng::Rng) -> f64,
) -> f64 {
    let unit_model = ForwardModel::new(truth).expect("valid truth");
    let g = truth.gravity_m_s2;
    let mut s = 0.0;
    let n = 60;
    for _ in 0..n {
        let up = unit(rng);
        let rate = rate_deg_s(rng).to_radians();
        let axis = unit(rng);
        let acc = rng.range(0.0, 50.0);
        let adir = unit(rng);
        let m = BodyMotion {
            f_o: BodySpecificForce {
                m_s2: up.map(|c| c * g),
            },
            omega: BodyRate {
                rad_s: axis.map(|c| c * rate),
            },
            omega_dot: BodyAngularAccel {
                rad_s2: adir.map(|c| c * acc),
            },
        };
        let u = unit_model.outputs(&m).raw;
        // What the device sees: the gyro's reading, corrected with the estimated model when there is one.
        let seen = match gyro {
            None => m,
            Some((gt, bt)) => {
                let w = linalg::mat_vec(gt, &m.omega.rad_s);
                let w: [f64; 3] = core::array::from_fn(|i| w[i] + bt[i]);
                let wd = linalg::mat_vec(gt, &m.omega_dot.rad_s2);
                let (w, wd) = match out.gyro.as_ref().and_then(|e| e.correction()) {
                    Some((gi, b)) => (
                        linalg::mat_vec(&gi, &core::array::from_fn(|i| w[i] - b[i])),
                        linalg::mat_vec(&gi, &wd),
                    ),
                    None => (w, wd),
                };
                BodyMotion {
                    f_o: m.f_o,
                    omega: BodyRate { rad_s: w },
                    omega_dot: BodyAngularAccel { rad_s2: wd },
                }
            }
        };
        let f = apply(
            rot,
            &compensate(&out.fitted, &out.calibration.lever_arms.r_m, g, &u, &seen),
        );
        s += (0..3).map(|i| (f[i] - up[i]).powi(2)).sum::<f64>();
    }
    (s / (3 * n) as f64).sqrt() * 1e6
}

/// The norm-only method (as hand-calibration tools do): `u0` and a lower-triangular `T = M⁻¹` such
/// that every static mean has |T (ū − u0)| = 1, unweighted Gauss–Newton with a numerical Jacobian.
pub(crate) fn norm_only(means: &[[f64; 3]]) -> Option<FittedStatic> {
    let mut p = [0.0; 9]; // u0 (3), T00, T10, T11, T20, T21, T22
    for i in 0..3 {
        let (lo, hi) = means
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), m| {
                (a.min(m[i]), b.max(m[i]))
            });
        p[i] = 0.5 * (lo + hi);
    }
    let k: [f64; 3] = core::array::from_fn(|i| {
        let (lo, hi) = means
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), m| {
                (a.min(m[i]), b.max(m[i]))
            });
        0.5 * (hi - lo)
    });
    p[3] = 1.0 / k[0];
    p[5] = 1.0 / k[1];
    p[8] = 1.0 / k[2];
    let t_of =
        |p: &[f64; 9]| -> RowMajor3 { [[p[3], 0.0, 0.0], [p[4], p[5], 0.0], [p[6], p[7], p[8]]] };
    let res = |p: &[f64; 9]| -> Vec<f64> {
        let t = t_of(p);
        means
            .iter()
            .map(|m| {
                let d: [f64; 3] = core::array::from_fn(|i| m[i] - p[i]);
                linalg::norm(&linalg::mat_vec(&t, &d)) - 1.0
            })
            .collect()
    };
    for _ in 0..50 {
        let r0 = res(&p);
        let mut jac = nalgebra::DMatrix::<f64>::zeros(means.len(), 9);
        for c in 0..9 {
            let h = 1e-7 * p[c].abs().max(1e-6 * p[3].abs());
            let mut q = p;
            q[c] += h;
            let r1 = res(&q);
            for k in 0..means.len() {
                jac[(k, c)] = (r1[k] - r0[k]) / h;
            }
        }
        let jt = jac.transpose();
        let step = (&jt * &jac)
            .cholesky()?
            .solve(&(&jt * nalgebra::DVector::from_vec(r0)));
        for c in 0..9 {
            p[c] -= step[c];
        }
        if step
            .iter()
            .zip(&p)
            .all(|(s, v)| s.abs() <= 1e-13 * v.abs().max(1e-6))
        {
            break;
        }
    }
    Some(FittedStatic {
        output_unit: shared::OutputUnit::Volts,
        m_out_per_g: linalg::inverse(&t_of(&p))?,
        zero_bias_out: [p[0], p[1], p[2]],
    })
}

/// Runs a case on the paper's unit.
pub fn run(case: &Case) -> CaseResult {
    let truth = testkit::paper_unit();
    let seeds = (0..case.seeds)
        .map(|seed| seed_result(case, &truth, seed))
        .collect();
    CaseResult {
        title: case.title.clone(),
        seeds,
    }
}

/// One seed of `case`: its session's statistics, the calibration of them and that calibration's
/// errors against `truth`.
fn seed_result(case: &Case, truth: &Calibration, seed: u64) -> SeedResult {
    let stats = seed_stats(case, truth, seed);
    let out = calibrate_session_stats(&case.plan, &stats, &case.options)
        .unwrap_or_else(|e| panic!("{}: seed {seed}: {e}", case.title));
    let mut rng = shared::rng::Rng::new(77 + seed, 0);
    let st = static_errors(truth, &out.fitted, &mut rng);
    let rot = st.rotation;
    let gy = case.gyro.as_ref();
    let dyn200_ug = dynamic_error(truth, &out, gy, &rot, &mut rng, &|_| 200.0);
    let dyn300_ug = dynamic_error(truth, &out, gy, &rot, &mut rng, &|r| r.range(0.0, 300.0));
    let (gyro_err, gyro_err_rotated) = gyro_errors(&out, case.gyro, &rot);
    let (tf, _) = truth.statics.to_fitted().expect("valid truth");
    let q_true = rotation_vector(&lq(&tf.m_out_per_g).1);
    let q_est = rotation_vector(&lq(&out.fitted.m_out_per_g).1);
    let norm_only_static_ug = case
        .norm_only
        .then(|| norm_only_errors(&case.plan, &stats, truth, seed));
    SeedResult {
        static_raw_ug: st.raw_worst_ug,
        static_ug: st.worst_ug,
        static_rms_ug: st.rms_ug,
        dyn200_ug,
        dyn300_ug,
        lever_err_m: core::array::from_fn(|i| {
            core::array::from_fn(|j| {
                out.calibration.lever_arms.r_m[i][j] - truth.lever_arms.r_m[i][j]
            })
        }),
        body_err_rad: core::array::from_fn(|c| q_est[c] - q_true[c]),
        body_sigma_rad: out.static_split.alignment_1sigma_rad,
        tilt_warning: out
            .warnings
            .iter()
            .any(|w| matches!(w, crate::estimate::note::Note::MountsTilted { .. })),
        norm_only_static_ug,
        gyro_err,
        gyro_err_rotated,
    }
}

/// The segment statistics of seed `seed` of `case`, from its generator, with the table's rate scale
/// error drawn when the case asks for one.
fn seed_stats(case: &Case, truth: &Calibration, seed: u64) -> Vec<SegmentStats> {
    let rate_scale = if case.table_rate_error {
        case.plan.table_rate_sigma_ppm() * 1e-6 * shared::rng::Rng::new(9000 + seed, 0).normal()
    } else {
        0.0
    };
    match case.generator {
        Generator::Rows => {
            let mut noise = NoiseModel {
                accel_white_mg: 1.0,
                gyro_white_deg_s: 0.05,
                table_tilt_deg: case.true_tilt_deg,
                ..NoiseModel::none()
            };
            if let Some((g, b)) = case.gyro {
                noise.gyro_matrix = g;
                noise.gyro_bias_deg_s = b.map(f64::to_degrees);
            }
            noise.table_rate_scale = rate_scale;
            crate::sim::stats::simulate_stats(truth, &case.plan, &noise, seed)
                .expect("valid simulation")
        }
        Generator::Stats => {
            let noise_out = 1e-3 * truth.statics.scale_out_per_g[0];
            let errors = TableErrors {
                attitude_deg: case.true_tilt_deg,
                gyro_noise_rad_s: 0.05f64.to_radians(),
                gyro: case.gyro,
                rate_scale,
                ..TableErrors::default()
            };
            let mut rng = shared::rng::Rng::new(1000 + seed, 0);
            testkit::noisy_stats(&case.plan, truth, noise_out, errors, &mut rng)
        }
    }
}

/// The gyro estimate's errors against the simulated gyro `gyro` (perfect when `None`): the
/// [`SeedResult::gyro_err`] and [`SeedResult::gyro_err_rotated`] of a seed whose body frame is off by
/// the common rotation `rot`.
fn gyro_errors(
    out: &CalibrationOutcome,
    gyro: Option<(RowMajor3, [f64; 3])>,
    rot: &Matrix3<f64>,
) -> (Option<GyroErrors>, Option<RowMajor3>) {
    let (gt, bt) = gyro.unwrap_or((crate::sim::session::IDENTITY, [0.0; 3]));
    let gyro_err_rotated = out.gyro.as_ref().map(|e| {
        let g = Matrix3::from_fn(|i, j| e.matrix[i][j]) * rot.transpose();
        core::array::from_fn(|i| core::array::from_fn(|j| g[(i, j)] - gt[i][j]))
    });
    let gyro_err = out.gyro.as_ref().map(|e| {
        (
            core::array::from_fn(|i| core::array::from_fn(|j| e.matrix[i][j] - gt[i][j])),
            core::array::from_fn(|i| e.bias_rad_s[i] - bt[i]),
            e.matrix_1sigma,
            e.bias_rad_s_1sigma,
        )
    });
    (gyro_err, gyro_err_rotated)
}

/// The norm-only method's static errors (worst, rms), µg, fitted to the static segments' means of
/// `stats`, on the same held-out attitudes as the seed's estimate.
fn norm_only_errors(
    plan: &Plan,
    stats: &[SegmentStats],
    truth: &Calibration,
    seed: u64,
) -> (f64, f64) {
    let means: Vec<[f64; 3]> = plan
        .segments
        .iter()
        .zip(stats)
        .filter(|(s, _)| s.is_static())
        .map(|(_, st)| st.mean_u)
        .collect();
    let f = norm_only(&means).expect("norm-only converges");
    let e = static_errors(truth, &f, &mut shared::rng::Rng::new(77 + seed, 0));
    (e.worst_ug, e.rms_ug)
}

/// The `q` quantile (nearest rank).
pub fn percentile(mut v: Vec<f64>, q: f64) -> f64 {
    v.sort_by(f64::total_cmp);
    let k = ((q * v.len() as f64).ceil() as usize).clamp(1, v.len()) - 1;
    v[k]
}

/// Root mean square.
pub fn rms(v: impl Iterator<Item = f64>) -> f64 {
    let (mut s, mut n) = (0.0, 0.0);
    for x in v {
        s += x * x;
        n += 1.0;
    }
    (s / n).sqrt()
}

impl CaseResult {
    /// 95th percentile of the static error after the common rotation, µg.
    pub fn static_p95_ug(&self) -> f64 {
        percentile(self.seeds.iter().map(|s| s.static_ug).collect(), 0.95)
    }
    /// 95th percentile of the static error as is, µg.
    pub fn static_raw_p95_ug(&self) -> f64 {
        percentile(self.seeds.iter().map(|s| s.static_raw_ug).collect(), 0.95)
    }
    /// RMS over seeds of the dynamic error at 200 °/s, µg.
    pub fn dyn200_ug(&self) -> f64 {
        rms(self.seeds.iter().map(|s| s.dyn200_ug))
    }
    /// RMS over seeds of the dynamic error to 300 °/s, µg.
    pub fn dyn300_ug(&self) -> f64 {
        rms(self.seeds.iter().map(|s| s.dyn300_ug))
    }
    /// RMS error of each lever-arm component over seeds, m.
    pub fn lever_rms_m(&self) -> RowMajor3 {
        core::array::from_fn(|i| {
            core::array::from_fn(|j| rms(self.seeds.iter().map(|s| s.lever_err_m[i][j])))
        })
    }
    /// The worst component's RMS lever-arm error, m.
    pub fn lever_worst_rms_m(&self) -> f64 {
        self.lever_rms_m()
            .iter()
            .flatten()
            .fold(0.0, |a: f64, b| a.max(*b))
    }
    /// Observed body-frame error spread / mean reported 1σ, pooled over the three axes.
    pub fn body_ratio(&self) -> f64 {
        let spread = rms(self.seeds.iter().flat_map(|s| s.body_err_rad));
        let sigma = rms(self.seeds.iter().flat_map(|s| s.body_sigma_rad));
        spread / sigma
    }
    /// Seeds whose report warned of a tilt.
    pub fn warned(&self) -> usize {
        self.seeds.iter().filter(|s| s.tilt_warning).count()
    }
    /// RMS over seeds and held-out attitudes of the static error after the common rotation, µg.
    pub fn static_rms_ug(&self) -> f64 {
        rms(self.seeds.iter().map(|s| s.static_rms_ug))
    }
    /// The norm-only method's 95th percentile worst and overall rms static error, µg.
    pub fn norm_only_ug(&self) -> Option<(f64, f64)> {
        let v: Vec<(f64, f64)> = self
            .seeds
            .iter()
            .filter_map(|s| s.norm_only_static_ug)
            .collect();
        (!v.is_empty()).then(|| {
            (
                percentile(v.iter().map(|x| x.0).collect(), 0.95),
                rms(v.iter().map(|x| x.1)),
            )
        })
    }
    /// Gyro figures: rms error and spread/mean 1σ of the scale entries (diagonal, ppm), the
    /// misalignment entries (off-diagonal, µrad) and the biases (°/s).
    pub fn gyro_figures(&self) -> Option<[(f64, f64); 3]> {
        let e: Vec<&(RowMajor3, [f64; 3], RowMajor3, [f64; 3])> = self
            .seeds
            .iter()
            .filter_map(|s| s.gyro_err.as_ref())
            .collect();
        if e.is_empty() {
            return None;
        }
        let pick = |diag: bool| {
            let err = rms(e.iter().flat_map(|x| {
                (0..9)
                    .filter(move |k| (k % 4 == 0) == diag)
                    .map(move |k| x.0[k / 3][k % 3])
            }));
            let sig = rms(e.iter().flat_map(|x| {
                (0..9)
                    .filter(move |k| (k % 4 == 0) == diag)
                    .map(move |k| x.2[k / 3][k % 3])
            }));
            (err, err / sig)
        };
        let (s, m) = (pick(true), pick(false));
        let b = rms(e.iter().flat_map(|x| x.1));
        let bs = rms(e.iter().flat_map(|x| x.3));
        Some([(s.0 * 1e6, s.1), (m.0 * 1e6, m.1), (b.to_degrees(), b / bs)])
    }

    /// RMS of the scale (diagonal, ppm) and misalignment (off-diagonal, µrad) errors of `G` after
    /// removing the common rotation.
    pub fn gyro_intrinsic(&self) -> Option<(f64, f64)> {
        let e: Vec<&RowMajor3> = self
            .seeds
            .iter()
            .filter_map(|s| s.gyro_err_rotated.as_ref())
            .collect();
        if e.is_empty() {
            return None;
        }
        let pick = |diag: bool| {
            rms(e.iter().flat_map(|x| {
                (0..9)
                    .filter(move |k| (k % 4 == 0) == diag)
                    .map(move |k| x[k / 3][k % 3])
            })) * 1e6
        };
        Some((pick(true), pick(false)))
    }

    /// One line per figure.
    pub fn print(&self) {
        if let Some((s, m)) = self.gyro_intrinsic() {
            eprintln!(
                "   gyro relative to the accelerometers (common rotation removed): scale rms {s:.1} ppm, \
                 misalignment rms {m:.1} µrad"
            );
        }
        if let Some([s, m, b]) = self.gyro_figures() {
            eprintln!(
                "   gyro as estimated (body frame of the fixture): scale rms {:.1} ppm (spread/σ {:.2}), \
                 misalignment rms {:.1} µrad (spread/σ {:.2}), bias rms {:.5} °/s (spread/σ {:.2})",
                s.0, s.1, m.0, m.1, b.0, b.1
            );
        }
        eprintln!("== {} ({} seeds)", self.title, self.seeds.len());
        eprintln!(
            "   static worst error (95th pct): {:.1} µg as is, {:.1} µg after the best common rotation \
             (rms {:.1} µg)",
            self.static_raw_p95_ug(),
            self.static_p95_ug(),
            self.static_rms_ug()
        );
        eprintln!(
            "   dynamic rms after the common rotation: {:.1} µg at 200 °/s, {:.1} µg to 300 °/s",
            self.dyn200_ug(),
            self.dyn300_ug()
        );
        let l = self.lever_rms_m();
        eprintln!(
            "   lever-arm rms error (µm): {:?}; worst {:.1} µm",
            l.map(|r| r.map(|v| (v * 1e7).round() / 10.0)),
            self.lever_worst_rms_m() * 1e6
        );
        eprintln!(
            "   body-frame error rms {:.2} µrad vs reported 1σ rms {:.2} µrad (ratio {:.2}); tilt warnings {}/{}",
            rms(self.seeds.iter().flat_map(|s| s.body_err_rad)) * 1e6,
            rms(self.seeds.iter().flat_map(|s| s.body_sigma_rad)) * 1e6,
            self.body_ratio(),
            self.warned(),
            self.seeds.len()
        );
        if let Some((w, r)) = self.norm_only_ug() {
            eprintln!(
                "   norm-only method, same data, after its best rotation: static worst error (95th pct) \
                 {w:.1} µg (rms {r:.1} µg)"
            );
        }
    }
}

//! A continuous hand-held session: a person holds the unit still in a series of positions and turns it
//! by hand between them, everything logged in one unlabelled CSV as a real logger would write it. The
//! test bed of `host segment` and of the gyro fit without a table (`estimate::handheld_gyro`).
//!
//! Positions are the built-in `hand` plan's 24 well-spread ups, each with a random heading. A turn is
//! one rotation about a fixed axis with a raised-cosine rate profile (rate 0 at both ends, peak
//! `2θ/T`). The hand's tremor is a sum of sinusoids (3–9 Hz) in angular rate and in linear
//! acceleration, present all the time; the gravity direction in body axes follows the integrated
//! tremor. Outputs come from the shared forward model (lever arms included); the gyro reads
//! `w = G·ω + b` plus white noise (docs/model.md §8).

use nalgebra::{UnitQuaternion, Vector3};
use recording::session::builtin::builtin_plan;
use shared::forward::{BodyMotion, ForwardModel};
use shared::linalg::{self, RowMajor3};
use shared::rng::Rng;
use shared::units::{BodyAngularAccel, BodyRate, BodySpecificForce};
use shared::Calibration;
use std::f64::consts::PI;
use std::io::Write;
use std::path::Path;

/// The gyro's truth: `w = matrix·ω_body + bias_rad_s` (docs/model.md §8).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GyroTruth {
    /// `G`, gyro output per body rate.
    pub matrix: RowMajor3,
    /// `b`, rad/s.
    pub bias_rad_s: [f64; 3],
}

/// The simulated unit's truth file: the accelerometer as a unit file, with the gyro's own table
/// (`host simulate-hand` writes it beside the CSV; the Python package returns it as text).
pub fn truth_toml(truth: &Calibration, gyro: &GyroTruth) -> String {
    format!(
        "{}\n# The simulated gyro: w = matrix·ω_body + bias (true body axes).\n[gyro]\nmatrix = {:?}\nbias_rad_s = {:?}\n",
        crate::unit_file::UnitFile::from_calibration(truth, None, None).to_toml(),
        gyro.matrix,
        gyro.bias_rad_s
    )
}

impl GyroTruth {
    /// Scale errors `scale_rel` per axis and small rotations of each gyro axis by the angles
    /// `misalign_rad` (row i's off-diagonals), bias `bias_rad_s`.
    pub fn new(scale_rel: [f64; 3], misalign_rad: RowMajor3, bias_rad_s: [f64; 3]) -> GyroTruth {
        let matrix = core::array::from_fn(|i| {
            core::array::from_fn(|j| {
                let e = if i == j { 1.0 } else { misalign_rad[i][j] };
                (1.0 + scale_rel[i]) * e
            })
        });
        GyroTruth { matrix, bias_rad_s }
    }

    /// The stated test gyro: 0.5 % scale, 0.5° misalignment, 0.5 °/s bias (signs mixed).
    pub(crate) fn half_percent() -> GyroTruth {
        let m = 0.5f64.to_radians();
        GyroTruth::new(
            [0.005, -0.005, 0.004],
            [[0.0, m, -m], [-m, 0.0, m], [m, m, 0.0]],
            [0.5, -0.5, 0.4].map(|d: f64| d.to_radians()),
        )
    }
}

/// What to simulate.
#[derive(Clone, Debug, PartialEq)]
pub struct HandSpec {
    /// Sample rate, Hz.
    pub rate_hz: f64,
    /// Up directions of the positions, body axes (the `hand` plan's by default).
    pub ups: Vec<[f64; 3]>,
    /// Hold duration range, s.
    pub hold_s: (f64, f64),
    /// Turn duration range, s.
    pub turn_s: (f64, f64),
    /// Peak turn rate, °/s.
    pub max_rate_deg_s: f64,
    /// Accelerometer white noise per sample, g.
    pub noise_g: f64,
    /// Tremor, rms of the linear acceleration per axis, g.
    pub tremor_g: f64,
    /// Tremor, rms of the angular rate per axis, °/s.
    pub tremor_deg_s: f64,
    /// Gyro white noise per sample, °/s.
    pub gyro_noise_deg_s: f64,
    /// The gyro.
    pub gyro: GyroTruth,
    /// Quantisation step of the accelerometer output (raw counts: 1), output unit; 0 = none.
    pub acc_step: f64,
    /// Tremor during the holds too (held in the hand); false: set down on a table, tremor only
    /// while turning.
    pub hold_tremor: bool,
    /// At each position, one whole turn about the vertical on the table before moving on, the unit
    /// set back against the same stop and held again (docs/model.md §7.2, `TableTurnSim`).
    pub table_turns: bool,
    /// Seed.
    pub seed: u64,
}

impl HandSpec {
    /// The stated hand session: 24 positions held 3–5 s, turns of 1–3 s up to 180 °/s, 1 mg noise
    /// at 200 Hz, tremor 1 mg and 0.2 °/s, gyro `GyroTruth::half_percent` with 0.05 °/s noise.
    pub fn standard(seed: u64) -> HandSpec {
        let ups = builtin_plan("hand")
            .and_then(Result::ok)
            .map(|p| p.segments.iter().map(|s| s.up_b).collect())
            .unwrap_or_default();
        HandSpec {
            rate_hz: 200.0,
            ups,
            hold_s: (3.0, 5.0),
            turn_s: (1.0, 3.0),
            max_rate_deg_s: 180.0,
            noise_g: 1e-3,
            tremor_g: 1e-3,
            tremor_deg_s: 0.2,
            gyro_noise_deg_s: 0.05,
            gyro: GyroTruth::half_percent(),
            acc_step: 0.0,
            hold_tremor: true,
            table_turns: false,
            seed,
        }
    }

    /// A six-face session (the classic bench method, docs/model.md §7.1): a cube set down on a table
    /// on each of its six faces in turn, each face's true up `placement_deg` off its body axis in a
    /// random direction, held 6–9 s, turned over by hand in 2–3 s between faces (+z, +x, +y, −z, −x,
    /// −y: the turns go about each body axis), `rounds` times over (each set-down its own placement).
    /// Noise as a consumer MEMS unit at 200 Hz: 150 µg/√Hz (1.5 mg per sample), gyro 0.01 °/s/√Hz
    /// (0.1 °/s per sample).
    pub fn six_faces(seed: u64, placement_deg: f64, rounds: usize) -> HandSpec {
        let mut rng = Rng::new(seed, 12);
        let faces = [
            [0.0, 0.0, 1.0],
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, 0.0, -1.0],
            [-1.0, 0.0, 0.0],
            [0.0, -1.0, 0.0],
        ];
        let ups = faces
            .iter()
            .cycle()
            .take(6 * rounds.max(1))
            .map(|n: &[f64; 3]| {
                // A random axis perpendicular to n, and the face turned about it by the placement.
                let r: [f64; 3] = core::array::from_fn(|_| rng.normal());
                let axis = linalg::cross(n, &r);
                let axis = Vector3::from(axis).normalize();
                let q = UnitQuaternion::from_axis_angle(
                    &nalgebra::Unit::new_normalize(axis),
                    placement_deg.to_radians(),
                );
                let u = q * Vector3::from(*n);
                [u.x, u.y, u.z]
            })
            .collect();
        HandSpec {
            ups,
            hold_s: (6.0, 9.0),
            turn_s: (2.0, 3.0),
            noise_g: 1.5e-3,
            gyro_noise_deg_s: 0.1,
            hold_tremor: false,
            ..HandSpec::standard(seed)
        }
    }
}

/// How a whole turn on the table is simulated: the unit's reference point [`Self::OFFSET_M`] from the
/// turn's axis (its centripetal and tangential acceleration reach the accelerometers), turned once,
/// either way, in 4–6 s (raised-cosine rate, peaks of 120–180 °/s) about the vertical, rocking on
/// the table by up to [`Self::ROCK_DEG`] about a horizontal axis in the middle of the turn (none at
/// its ends), and set back against its stop with an error of [`Self::STOP_SIGMA_DEG`] (1σ).
pub(crate) struct TableTurnSim;

impl TableTurnSim {
    /// Distance of the unit's reference point from the turn's axis, m.
    pub const OFFSET_M: f64 = 0.03;
    /// Amplitude of the rocking, degrees.
    pub const ROCK_DEG: f64 = 0.1;
    /// 1σ of the heading's return to the stop, degrees.
    pub const STOP_SIGMA_DEG: f64 = 0.05;
}

/// One logged row: time, accelerometer (output unit), gyro (rad/s).
pub type HandRow = (f64, [f64; 3], [f64; 3]);

/// The simulated recording and where the holds really were.
#[derive(Clone, Debug)]
pub struct HandSession {
    /// The rows.
    pub rows: Vec<HandRow>,
    /// Each hold's first and last time, s, and its up, body axes.
    pub holds: Vec<(f64, f64, [f64; 3])>,
}

/// Tremor: three sinusoids per axis with random frequency and phase, scaled to an rms.
struct Tremor {
    parts: Vec<[(f64, f64, f64); 3]>,
}

impl Tremor {
    fn new(rng: &mut Rng, rms: f64) -> Tremor {
        // Three equal sinusoids of amplitude A have rms A·√(3/2).
        let a = rms / 1.5f64.sqrt();
        let parts = (0..3)
            .map(|_| {
                core::array::from_fn(|_| {
                    let f = 3.0 + 6.0 * uniform(rng);
                    (a, 2.0 * PI * f, 2.0 * PI * uniform(rng))
                })
            })
            .collect();
        Tremor { parts }
    }

    /// Value, derivative and integral (from −∞, zero mean) at `t`, times `k`.
    fn at(&self, t: f64, k: f64) -> ([f64; 3], [f64; 3], [f64; 3]) {
        let (mut v, mut d, mut i) = ([0.0; 3], [0.0; 3], [0.0; 3]);
        for p in &self.parts {
            for j in 0..3 {
                let (a, w, ph) = p[j];
                let a = a * k;
                v[j] += a * (w * t + ph).sin();
                d[j] += a * w * (w * t + ph).cos();
                i[j] -= a / w * (w * t + ph).cos();
            }
        }
        (v, d, i)
    }
}

fn uniform(rng: &mut Rng) -> f64 {
    ((rng.next_u64() >> 11) as f64 + 0.5) / (1u64 << 53) as f64
}

/// Body-to-world attitude with body `up` along world z and heading `psi`.
fn attitude(up: [f64; 3], psi: f64) -> UnitQuaternion<f64> {
    let level = UnitQuaternion::rotation_between(&Vector3::from(up), &Vector3::z())
        .unwrap_or_else(|| UnitQuaternion::from_axis_angle(&Vector3::x_axis(), PI));
    UnitQuaternion::from_axis_angle(&Vector3::z_axis(), psi) * level
}

/// One sample's outputs: the forward model, the hand's tremor and the sensors' noise.
struct Sampler<'a> {
    model: &'a ForwardModel,
    spec: &'a HandSpec,
    g: f64,
    tremor_w: &'a Tremor,
    tremor_a: &'a Tremor,
    scales: [f64; 3],
}

impl Sampler<'_> {
    /// Accelerometer and gyro at `t` in attitude `q` with the turn's body rate, its derivative and
    /// the reference point's own acceleration (a table turn's, about an axis off it), body axes.
    fn sample(
        &self,
        t: f64,
        q: &UnitQuaternion<f64>,
        [w_turn, wd_turn, a_b]: [[f64; 3]; 3],
        rng: &mut Rng,
    ) -> ([f64; 3], [f64; 3]) {
        // On a table (no hold tremor) the tremor is the hand's, while turning only.
        let k = if self.spec.hold_tremor || w_turn != [0.0; 3] {
            1.0
        } else {
            0.0
        };
        let (tw, twd, tint) = self.tremor_w.at(t, k);
        let (ta, _, _) = self.tremor_a.at(t, k);
        let up0 = q.inverse_transform_vector(&Vector3::z());
        // Small tremor rotation δ: a world vector seen in body axes becomes v − δ × v.
        let up0 = [up0.x, up0.y, up0.z];
        let turn = linalg::cross(&tint, &up0);
        let up: [f64; 3] = core::array::from_fn(|j| up0[j] - turn[j]);
        let omega: [f64; 3] = core::array::from_fn(|j| w_turn[j] + tw[j]);
        let motion = BodyMotion {
            f_o: BodySpecificForce {
                m_s2: core::array::from_fn(|j| self.g * up[j] + ta[j] + a_b[j]),
            },
            omega: BodyRate { rad_s: omega },
            omega_dot: BodyAngularAccel {
                rad_s2: core::array::from_fn(|j| wd_turn[j] + twd[j]),
            },
        };
        let raw = self.model.outputs(&motion).raw;
        let acc = core::array::from_fn(|i| {
            let u = raw[i] + self.spec.noise_g * self.scales[i] * rng.normal();
            if self.spec.acc_step > 0.0 {
                (u / self.spec.acc_step).round() * self.spec.acc_step
            } else {
                u
            }
        });
        let gw = linalg::mat_vec(&self.spec.gyro.matrix, &omega);
        let gyro = core::array::from_fn(|i| {
            gw[i]
                + self.spec.gyro.bias_rad_s[i]
                + self.spec.gyro_noise_deg_s.to_radians() * rng.normal()
        });
        (acc, gyro)
    }
}

/// Simulates the session for a unit `truth` (its output unit is the file's).
pub fn simulate_hand(truth: &Calibration, spec: &HandSpec) -> HandSession {
    let model = ForwardModel::new(truth).expect("a valid simulated unit");
    let g = truth.gravity_m_s2;
    let mut rng = Rng::new(spec.seed, 11);
    let tremor_w = Tremor::new(&mut rng, spec.tremor_deg_s.to_radians());
    let tremor_a = Tremor::new(&mut rng, spec.tremor_g * g);
    let dt = 1.0 / spec.rate_hz;
    let fitted = truth.statics.to_fitted().expect("a valid simulated unit").0;
    let scales = fitted.m_out_per_g.map(|row| linalg::norm(&row));
    let max_rate = spec.max_rate_deg_s.to_radians();
    let mut rows = Vec::new();
    let mut holds = Vec::new();
    let mut t = 0.0;
    let mut k = 0u64;
    let mut q = attitude(spec.ups[0], 2.0 * PI * uniform(&mut rng));
    let sampler = Sampler {
        model: &model,
        spec,
        g,
        tremor_w: &tremor_w,
        tremor_a: &tremor_a,
        scales,
    };
    let sample = |t, q: &_, w_turn, wd_turn, a_b, rng: &mut Rng| {
        sampler.sample(t, q, [w_turn, wd_turn, a_b], rng)
    };
    for (p, up) in spec.ups.iter().enumerate() {
        for again in [false, true] {
            if again {
                if !spec.table_turns {
                    break;
                }
                let turn = table_turn(&q, &mut rng);
                let t0 = t;
                while t < t0 + turn.duration_s {
                    let (qt, w_b, wd_b, a_b) = turn.at(t - t0);
                    let (a, w) = sample(t, &qt, w_b, wd_b, a_b, &mut rng);
                    rows.push((t, a, w));
                    k += 1;
                    t = k as f64 * dt;
                }
                q = turn.end();
            }
            let hold = spec.hold_s.0 + (spec.hold_s.1 - spec.hold_s.0) * uniform(&mut rng);
            let t0 = t;
            while t < t0 + hold {
                let (a, w) = sample(t, &q, [0.0; 3], [0.0; 3], [0.0; 3], &mut rng);
                rows.push((t, a, w));
                k += 1;
                t = k as f64 * dt;
            }
            let t_last = rows.last().map_or(t0, |r| r.0);
            holds.push((t0, t_last, *up));
        }
        let Some(next_up) = spec.ups.get(p + 1) else {
            break;
        };
        let q1 = attitude(*next_up, 2.0 * PI * uniform(&mut rng));
        let delta = q1 * q.inverse();
        let (axis_w, angle) = delta.axis_angle().unwrap_or((Vector3::z_axis(), 0.0));
        let drawn = spec.turn_s.0 + (spec.turn_s.1 - spec.turn_s.0) * uniform(&mut rng);
        let dur = drawn.max(2.0 * angle / max_rate);
        let t0 = t;
        let q0 = q;
        while t < t0 + dur {
            let s = (t - t0) / dur;
            let th = angle * (s - (2.0 * PI * s).sin() / (2.0 * PI));
            let rate = angle / dur * (1.0 - (2.0 * PI * s).cos());
            let acc = angle / (dur * dur) * 2.0 * PI * (2.0 * PI * s).sin();
            let qt = UnitQuaternion::from_axis_angle(&axis_w, th) * q0;
            let ab = qt.inverse_transform_vector(&axis_w);
            let (a, w) = sample(
                t,
                &qt,
                [ab.x * rate, ab.y * rate, ab.z * rate],
                [ab.x * acc, ab.y * acc, ab.z * acc],
                [0.0; 3],
                &mut rng,
            );
            rows.push((t, a, w));
            k += 1;
            t = k as f64 * dt;
        }
        q = q1;
    }
    HandSession { rows, holds }
}

/// One whole table turn from the attitude `q0` ([`TableTurnSim`]).
struct TableTurnPath {
    q0: UnitQuaternion<f64>,
    /// Signed angle turned about world z (a whole turn plus the stop's error), rad.
    angle: f64,
    duration_s: f64,
    /// Horizontal axis of the rocking, world.
    rock_axis: nalgebra::Unit<Vector3<f64>>,
    /// Rocking frequency, Hz.
    rock_hz: f64,
    /// Reference point from the turn's axis, body axes, m.
    offset_b: Vector3<f64>,
}

fn table_turn(q0: &UnitQuaternion<f64>, rng: &mut Rng) -> TableTurnPath {
    let sign = if uniform(rng) < 0.5 { -1.0 } else { 1.0 };
    let angle = sign * 2.0 * PI + TableTurnSim::STOP_SIGMA_DEG.to_radians() * rng.normal();
    let duration_s = 4.0 + 2.0 * uniform(rng);
    let a = 2.0 * PI * uniform(rng);
    let rock_axis = nalgebra::Unit::new_normalize(Vector3::new(a.cos(), a.sin(), 0.0));
    let rock_hz = 1.0 + 2.0 * uniform(rng);
    let b = 2.0 * PI * uniform(rng);
    let offset_w = Vector3::new(b.cos(), b.sin(), 0.0) * TableTurnSim::OFFSET_M;
    TableTurnPath {
        q0: *q0,
        angle,
        duration_s,
        rock_axis,
        rock_hz,
        offset_b: q0.inverse_transform_vector(&offset_w),
    }
}

impl TableTurnPath {
    /// Body-to-world attitude `s` seconds into the turn: rocked, then turned about world z.
    fn attitude(&self, s: f64) -> UnitQuaternion<f64> {
        let x = (s / self.duration_s).clamp(0.0, 1.0);
        let th = self.angle * (x - (2.0 * PI * x).sin() / (2.0 * PI));
        let rock = TableTurnSim::ROCK_DEG.to_radians()
            * (PI * x).sin().powi(2)
            * (2.0 * PI * self.rock_hz * s).sin();
        UnitQuaternion::from_axis_angle(&self.rock_axis, rock)
            * UnitQuaternion::from_axis_angle(&Vector3::z_axis(), th)
            * self.q0
    }

    /// Body rate (rad/s), its derivative and the reference point's acceleration (m/s², body axes)
    /// by central differences of the attitude (exact to far below the sensors' noise).
    fn motion(&self, s: f64) -> ([f64; 3], [f64; 3], [f64; 3]) {
        let h = 1e-4;
        let rate = |s: f64| {
            (self.attitude(s - h).inverse() * self.attitude(s + h)).scaled_axis() / (2.0 * h)
        };
        let w = rate(s);
        let wd = (rate(s + h) - rate(s - h)) / (2.0 * h);
        let h2 = 1e-3;
        let pos = |s: f64| self.attitude(s) * self.offset_b;
        let a_w = (pos(s + h2) - 2.0 * pos(s) + pos(s - h2)) / (h2 * h2);
        let a_b = self.attitude(s).inverse_transform_vector(&a_w);
        ([w.x, w.y, w.z], [wd.x, wd.y, wd.z], [a_b.x, a_b.y, a_b.z])
    }

    /// Attitude, body rate, its derivative and the acceleration `s` seconds into the turn.
    fn at(&self, s: f64) -> (UnitQuaternion<f64>, [f64; 3], [f64; 3], [f64; 3]) {
        let (w, wd, a) = self.motion(s);
        (self.attitude(s), w, wd, a)
    }

    /// The attitude after the turn, set back against the stop.
    fn end(&self) -> UnitQuaternion<f64> {
        self.attitude(self.duration_s)
    }
}

/// How the CSV is laid out, as a logger would.
#[derive(Clone, Debug, PartialEq)]
pub struct LoggerLayout {
    /// Header names of acc x y z, gyro x y z.
    pub columns: [String; 6],
    /// Time column name (seconds), or `None` for a sample-index column named `sample`.
    pub time_column: Option<String>,
    /// Gyro written in °/s (else rad/s).
    pub gyro_deg_s: bool,
    /// An extra column (temperature) written first.
    pub extra_column: bool,
    /// Added to every accelerometer value (an unsigned output's mid-scale zero, e.g. 32768 counts).
    pub acc_offset: f64,
    /// The gyro written as whole counts at this scale, LSB per °/s (overrides `gyro_deg_s`).
    pub gyro_lsb_per_dps: Option<f64>,
}

impl LoggerLayout {
    /// A row's accelerometer and gyro values as this layout writes them: the offset added to the
    /// accelerometer, the gyro in °/s, rad/s or whole counts.
    pub fn written(&self, row: &HandRow) -> ([f64; 3], [f64; 3]) {
        let k = match self.gyro_lsb_per_dps {
            Some(lsb) => 180.0 / PI * lsb,
            None if self.gyro_deg_s => 180.0 / PI,
            None => 1.0,
        };
        let gyro = |x: f64| match self.gyro_lsb_per_dps {
            Some(_) => (x * k).round(),
            None => x * k,
        };
        (row.1.map(|a| a + self.acc_offset), row.2.map(gyro))
    }
}

impl Default for LoggerLayout {
    fn default() -> Self {
        LoggerLayout {
            columns: recording::session::import::DEFAULT_COLUMNS.map(String::from),
            time_column: Some("t".into()),
            gyro_deg_s: true,
            extra_column: false,
            acc_offset: 0.0,
            gyro_lsb_per_dps: None,
        }
    }
}

/// Writes `rows` as one unlabelled CSV.
pub fn write_logger_csv(
    path: &Path,
    rows: &[HandRow],
    layout: &LoggerLayout,
) -> std::io::Result<()> {
    let mut out = std::io::BufWriter::new(std::fs::File::create(path)?);
    let mut header: Vec<String> = Vec::new();
    if layout.extra_column {
        header.push("temp_c".into());
    }
    header.push(
        layout
            .time_column
            .clone()
            .unwrap_or_else(|| "sample".into()),
    );
    header.extend(layout.columns.iter().cloned());
    writeln!(out, "{}", header.join(","))?;
    for (i, row) in rows.iter().enumerate() {
        if layout.extra_column {
            write!(out, "25.0,")?;
        }
        match layout.time_column {
            Some(_) => write!(out, "{}", row.0)?,
            None => write!(out, "{i}")?,
        }
        let (a, w) = layout.written(row);
        writeln!(
            out,
            ",{},{},{},{},{},{}",
            a[0], a[1], a[2], w[0], w[1], w[2]
        )?;
    }
    out.into_inner().map_err(|e| e.into_error())?.sync_all()
}

/// A MEMS-like unit whose outputs are in `unit` (m/s², g or counts at 4096 per g): scale errors of
/// about 1 %, biases of about 5–20 mg, sensing axes 0.3–0.7° off the body axes, lever arms of a few
/// millimetres.
pub fn logger_unit(unit: shared::OutputUnit) -> Calibration {
    let per_g = match unit {
        shared::OutputUnit::MetresPerSecondSquared => shared::STANDARD_GRAVITY_M_S2,
        shared::OutputUnit::StandardGravity => 1.0,
        shared::OutputUnit::Lsb => 4096.0,
        shared::OutputUnit::Volts => 0.4,
    };
    let zero = if unit == shared::OutputUnit::Volts {
        2.5
    } else {
        0.0
    };
    Calibration {
        statics: shared::StaticParams {
            output_unit: unit,
            zero_bias_out: [0.012, -0.02, 0.005].map(|b| zero + b * per_g),
            scale_out_per_g: [1.011, 0.992, 1.006].map(|k| k * per_g),
            installation_angles_deg: [[0.6, 90.4, 89.7], [89.5, 0.55, 90.3], [90.35, 89.45, 0.45]],
        },
        lever_arms: shared::LeverArms {
            r_m: [
                [0.004, 0.001, -0.002],
                [-0.001, 0.005, 0.001],
                [0.002, -0.002, 0.003],
            ],
        },
        reference: shared::ReferencePoint::TableAxis,
        gravity_m_s2: shared::STANDARD_GRAVITY_M_S2,
        gyro: None,
        temperature: None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A whole turn on the table: halfway (peak rate, no angular acceleration; without rocking) the
    /// reference point 3 cm off the axis feels only the centripetal ω²r, horizontal; over the turn
    /// (rocking) the body rate integrates to the angle about up, to the rocking's size across it.
    #[test]
    fn a_table_turn_has_its_centripetal_force_and_turns_its_angle_about_up() {
        let q0 = attitude([0.0, 0.6, 0.8], 0.7);
        let up = q0.inverse_transform_vector(&Vector3::z());
        let flat = TableTurnPath {
            rock_hz: 0.0,
            ..table_turn(&q0, &mut Rng::new(8, 0))
        };
        let mid = 0.5 * flat.duration_s;
        let (w, wd, a) = flat.motion(mid);
        let omega = Vector3::from(w).norm();
        assert!((omega - 2.0 * flat.angle.abs() / flat.duration_s).abs() < 1e-6 * omega);
        assert!(Vector3::from(wd).norm() < 1e-4, "{wd:?}");
        let a = Vector3::from(a);
        let want = omega * omega * TableTurnSim::OFFSET_M;
        assert!((a.norm() - want).abs() < 1e-4 * want, "{a} against {want}");
        assert!(a.dot(&up).abs() < 1e-4 * want, "{a}");
        let path = table_turn(&q0, &mut Rng::new(8, 0));
        let n = 4000;
        let dt = path.duration_s / n as f64;
        let integral: Vector3<f64> = (0..n)
            .map(|i| Vector3::from(path.motion((i as f64 + 0.5) * dt).0) * dt)
            .sum();
        let along = integral.dot(&up);
        assert!(
            (along - path.angle).abs() < 1e-4,
            "{along} against {}",
            path.angle
        );
        let across = (integral - up * along).norm().to_degrees();
        assert!(
            across < 2.0 * 360.0 * TableTurnSim::ROCK_DEG.to_radians(),
            "{across}°"
        );
        assert!(path.end().angle_to(&q0).to_degrees() < 0.3);
    }
}

//! The virtual unit on a virtual rate table: `host simulate`.
//!
//! Every sample goes through the one forward model of the shared crate
//! (`TableState::motion` → `ForwardModel::outputs`), then through the noise model: accelerometer white
//! noise, bias random walk and ADC quantisation; table attitude error (a random tilt per mount) and
//! rate error (scale and offset); gyro white noise and bias. The random numbers come from xoshiro256++
//! seeded by SplitMix64 with one stream per noise source, and the normal deviates from the polar method
//! with `libm`'s logarithm: the bytes of a simulated session depend only on the inputs and the seed,
//! not on the platform or on a dependency's version, and switching one noise source on or off does not
//! change the draws of the others.

use super::sensor_noise::SensorNoise;
use super::thermal::{ThermalSim, ThermalState};
use crate::estimate::note::Note;
use crate::unit_file::UnitFile;
use recording::session::{Plan, PlanError, SegmentPlan};
use recording::session::{RecordingError, SessionWriter};
use serde::{Deserialize, Serialize};
use shared::forward::{ForwardModel, TableState};
use shared::linalg;
use shared::rng::Rng;
use shared::Calibration;
use std::collections::BTreeMap;
use std::path::Path;

/// The file a simulated session's truth is written to.
pub const TRUTH_FILE: &str = "truth.toml";

/// What noise to add. Every field has a default (`[noise]` in a unit file may give any subset).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct NoiseModel {
    /// Accelerometer white noise per sample, 1σ, mg (converted with each axis's scale factor).
    pub accel_white_mg: f64,
    /// ADC quantisation step, output unit (V or LSB); 0 = none.
    pub accel_quantum_out: f64,
    /// Accelerometer bias random walk, mg/√s (each axis starts at 0 at the session's start).
    pub accel_bias_walk_mg_sqrt_s: f64,
    /// Table attitude error: each mount's "up" is tilted by a random angle, 1σ per tilt axis, degrees.
    pub table_tilt_deg: f64,
    /// Table rate scale error (fraction; 1e-4 = 100 ppm), applied to spinning segments.
    pub table_rate_scale: f64,
    /// Table rate offset, °/s, applied to spinning segments.
    pub table_rate_offset_deg_s: f64,
    /// Gyro white noise per sample, 1σ, °/s.
    pub gyro_white_deg_s: f64,
    /// Gyro bias, body axes, °/s.
    pub gyro_bias_deg_s: [f64; 3],
    /// Gyro scale and misalignment: the gyro reads `G ω + bias` (docs/model.md §8); identity =
    /// perfect. A unit file's `[gyro]` table sets it (and adds its bias).
    pub gyro_matrix: [[f64; 3]; 3],
    /// Accelerometer flicker (1/f) bias noise, as its bias instability B, mg (Allan floor 0.664 B).
    pub accel_flicker_mg: f64,
    /// Gyro bias random walk, °/s/√s, the same on the three axes (each axis starts at 0 at the
    /// session's start).
    pub gyro_bias_walk_deg_s_sqrt_s: f64,
    /// Gyro bias random walk per axis (x, y, z), °/s/√s, in place of
    /// `gyro_bias_walk_deg_s_sqrt_s` when given: a unit whose axes wander differently
    /// (docs/model.md §11.6). Absent from a file that does not give it.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub gyro_bias_walk_per_axis_deg_s_sqrt_s: Option<[f64; 3]>,
    /// Gyro flicker (1/f) bias noise, as its bias instability B, °/s.
    pub gyro_flicker_deg_s: f64,
}

/// The identity, the perfect gyro's matrix.
pub(crate) use shared::linalg::IDENTITY;

/// A gyro matrix with relative scale errors `scale` and every off-diagonal entry of magnitude
/// `misalignment_rad` with the signs `[[·, +, −], [+, ·, +], [−, −, ·]]` (a mix of axis rotation and
/// non-orthogonality, so no change of body frame absorbs it).
pub fn gyro_matrix(scale: [f64; 3], misalignment_rad: f64) -> [[f64; 3]; 3] {
    const SIGN: [[f64; 3]; 3] = [[0.0, 1.0, -1.0], [1.0, 0.0, 1.0], [-1.0, -1.0, 0.0]];
    std::array::from_fn(|i| {
        std::array::from_fn(|j| {
            if i == j {
                1.0 + scale[i]
            } else {
                SIGN[i][j] * misalignment_rad
            }
        })
    })
}

impl Default for NoiseModel {
    /// 1 mg accelerometer white noise, 0.05 °/s gyro white noise, nothing else.
    fn default() -> Self {
        NoiseModel {
            accel_white_mg: 1.0,
            accel_quantum_out: 0.0,
            accel_bias_walk_mg_sqrt_s: 0.0,
            table_tilt_deg: 0.0,
            table_rate_scale: 0.0,
            table_rate_offset_deg_s: 0.0,
            gyro_white_deg_s: 0.05,
            gyro_bias_deg_s: [0.0; 3],
            gyro_matrix: IDENTITY,
            accel_flicker_mg: 0.0,
            gyro_bias_walk_deg_s_sqrt_s: 0.0,
            gyro_bias_walk_per_axis_deg_s_sqrt_s: None,
            gyro_flicker_deg_s: 0.0,
        }
    }
}

impl NoiseModel {
    /// No noise and no table error at all: the outputs are exactly the forward model's.
    pub fn none() -> Self {
        NoiseModel {
            accel_white_mg: 0.0,
            gyro_white_deg_s: 0.0,
            ..NoiseModel::default()
        }
    }

    /// The gyro's bias random walk on each axis, °/s/√s: the per-axis strengths where given, else
    /// the one strength on all three.
    pub fn gyro_bias_walk_axes(&self) -> [f64; 3] {
        self.gyro_bias_walk_per_axis_deg_s_sqrt_s
            .unwrap_or([self.gyro_bias_walk_deg_s_sqrt_s; 3])
    }

    /// The gyro's bias random walk as one strength, °/s/√s: the one given, or the rms of the
    /// per-axis strengths (as `--bias-walk-from` takes a `noise.json`'s three gyro axes).
    pub fn gyro_bias_walk_one(&self) -> f64 {
        match self.gyro_bias_walk_per_axis_deg_s_sqrt_s {
            None => self.gyro_bias_walk_deg_s_sqrt_s,
            Some(k) => (k.iter().map(|k| k * k).sum::<f64>() / 3.0).sqrt(),
        }
    }

    /// The `[noise]` table of a unit file, over the defaults; `None` when there is none.
    pub fn from_unit_file(unit: &UnitFile) -> Result<Option<NoiseModel>, SimulateError> {
        match unit.other.get("noise") {
            None => Ok(None),
            Some(v) => v
                .clone()
                .try_into::<NoiseModel>()
                .map(Some)
                .map_err(|e| SimulateError::NoiseTable(Box::new(e))),
        }
    }

    /// Checks that every value is finite and every σ non-negative.
    pub fn validate(&self) -> Result<(), SimulateError> {
        let sigmas = [
            ("accel_white_mg", self.accel_white_mg),
            ("accel_quantum_out", self.accel_quantum_out),
            ("accel_bias_walk_mg_sqrt_s", self.accel_bias_walk_mg_sqrt_s),
            ("table_tilt_deg", self.table_tilt_deg),
            ("gyro_white_deg_s", self.gyro_white_deg_s),
            ("accel_flicker_mg", self.accel_flicker_mg),
            (
                "gyro_bias_walk_deg_s_sqrt_s",
                self.gyro_bias_walk_deg_s_sqrt_s,
            ),
            ("gyro_flicker_deg_s", self.gyro_flicker_deg_s),
        ]
        .into_iter()
        .chain(
            self.gyro_bias_walk_per_axis_deg_s_sqrt_s
                .into_iter()
                .flatten()
                .map(|v| ("gyro_bias_walk_per_axis_deg_s_sqrt_s", v)),
        );
        for (name, v) in sigmas {
            if !(v.is_finite() && v >= 0.0) {
                return Err(SimulateError::Noise(format!(
                    "{name} = {v} must be a finite number ≥ 0"
                )));
            }
        }
        let others = [self.table_rate_scale, self.table_rate_offset_deg_s]
            .into_iter()
            .chain(self.gyro_bias_deg_s)
            .chain(self.gyro_matrix.into_iter().flatten());
        if others.into_iter().any(|v| !v.is_finite()) {
            return Err(SimulateError::Noise(
                "table_rate_scale, table_rate_offset_deg_s, gyro_bias_deg_s and gyro_matrix must be finite"
                    .into(),
            ));
        }
        Ok(())
    }
}

/// Why a simulation cannot run.
#[derive(Debug, thiserror::Error)]
pub enum SimulateError {
    /// The unit's parameters are unusable.
    #[error("the unit to simulate is not usable")]
    Unit(#[source] crate::unit_file::UnitFileInvalid),
    /// The unit file's `[thermal]` table is not a thermal model.
    #[error("the unit to simulate is not usable: [thermal]")]
    ThermalTable(#[source] Box<toml::de::Error>),
    /// The thermal model's values are not finite and non-negative.
    #[error(
        "the unit to simulate is not usable: [thermal]: time constants, noise and quantum must \
         be finite and ≥ 0"
    )]
    ThermalValues,
    /// The unit's parameters do not make a forward model.
    #[error("the unit to simulate is not usable")]
    Params(#[source] shared::params::ParamsError),
    /// The unit file's `[noise]` table is not a noise model.
    #[error("noise model: [noise] in the unit file")]
    NoiseTable(#[source] Box<toml::de::Error>),
    /// The plan is unusable for simulation.
    #[error(transparent)]
    Plan(PlanError),
    /// A noise parameter is wrong.
    #[error("noise model: {0}")]
    Noise(String),
    /// Writing the session failed.
    #[error(transparent)]
    Recording(#[from] RecordingError),
}

/// What a simulation did, beyond the samples.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct SimulationSummary {
    /// The seed.
    pub seed: u64,
    /// Rows produced.
    pub rows: u64,
    /// The "up" actually used for each mount (after the drawn tilt), body axes.
    pub mount_up_b: BTreeMap<String, [f64; 3]>,
    /// The tilt drawn for each mount, degrees.
    pub mount_tilt_deg: BTreeMap<String, f64>,
    /// Notes for the user (e.g. the plan's output unit was changed to the unit's).
    #[serde(skip)]
    pub notes: Vec<Note>,
}

// The random streams, one per noise source (the module docs); the sensors' are drawn from in
// `super::sensor_noise`.
pub(super) const STREAM_ACCEL: u64 = 1;
pub(super) const STREAM_GYRO: u64 = 2;
pub(super) const STREAM_WALK: u64 = 3;
const STREAM_TILT: u64 = 4;
pub(super) const STREAM_FLICKER: u64 = 5;
pub(super) const STREAM_GYRO_WALK: u64 = 6;
/// The temperature sensor's noise (a high stream number, clear of any new noise source's).
const STREAM_TEMPERATURE: u64 = 16;

/// `up` tilted by small angles (radians) about the two axes perpendicular to it that the estimator
/// uses for a mount's tilt unknowns (`estimate::model::tilt_basis`), renormalised.
pub(crate) fn tilt(up: [f64; 3], n1: f64, n2: f64) -> [f64; 3] {
    let e = crate::estimate::model::tilt_basis(&up);
    let v: [f64; 3] = std::array::from_fn(|j| up[j] + n1 * e[0][j] + n2 * e[1][j]);
    let n = linalg::norm(&v);
    v.map(|c| c / n)
}

/// Simulates `plan` on `cal`, handing each row to `sink(segment, t_s, u, w_rad_s)`.
/// Time runs on across segments from 0 at `1 / sample_rate_hz` per row.
pub fn simulate_rows<E>(
    cal: &Calibration,
    plan: &Plan,
    noise: &NoiseModel,
    seed: u64,
    mut sink: impl FnMut(&str, f64, &[f64; 3], &[f64; 3]) -> Result<(), E>,
) -> Result<Result<SimulationSummary, E>, SimulateError> {
    let thermal = ThermalSim::default();
    simulate_rows_with_temperature(cal, plan, noise, &thermal, seed, |seg, t, u, w, _| {
        sink(seg, t, u, w)
    })
}

/// [`simulate_rows`] with the unit's temperature (`sink`'s last argument, the sensor's reading, °C):
/// the chamber follows the plan's set-points and `cal.temperature`, when present, moves the biases
/// and scale factors with the die's temperature ([`super::thermal`]).
pub fn simulate_rows_with_temperature<E>(
    cal: &Calibration,
    plan: &Plan,
    noise: &NoiseModel,
    thermal: &ThermalSim,
    seed: u64,
    mut sink: impl FnMut(&str, f64, &[f64; 3], &[f64; 3], f64) -> Result<(), E>,
) -> Result<Result<SimulationSummary, E>, SimulateError> {
    let model = simulable_model(cal, plan, noise, thermal)?;
    let mut sim = RowSimulator::new(cal, model, plan, noise, thermal, seed);
    for seg in &plan.segments {
        if let Err(e) = sim.segment(seg, &mut sink) {
            return Ok(Err(e));
        }
    }
    sim.summary.rows = sim.index;
    Ok(Ok(sim.summary))
}

/// Checks the inputs a simulation needs (a valid plan with a true attitude and a duration for every
/// segment, valid noise and thermal models) and returns the unit's forward model.
fn simulable_model(
    cal: &Calibration,
    plan: &Plan,
    noise: &NoiseModel,
    thermal: &ThermalSim,
) -> Result<ForwardModel, SimulateError> {
    plan.validate().map_err(SimulateError::Plan)?;
    noise.validate()?;
    thermal.validate()?;
    let model = ForwardModel::new(cal).map_err(SimulateError::Params)?;
    if let Some(s) = plan.segments.iter().find(|s| !s.has_up()) {
        return Err(SimulateError::Plan(PlanError::Invalid(format!(
            "segment '{}' has no up_b; simulate needs the true attitude of every segment (a free \
             attitude's up_b is where the simulated hand holds the unit)",
            s.name
        ))));
    }
    if let Some(s) = plan.segments.iter().find(|s| s.duration_s.is_none()) {
        return Err(SimulateError::Plan(PlanError::Invalid(format!(
            "segment '{}' has no duration_s; simulate needs one for every segment",
            s.name
        ))));
    }
    Ok(model)
}

/// The gyro bias's change with the die's temperature `die_c` (docs/model.md §9), rad/s; zero
/// without a temperature model.
fn gyro_thermal_bias(cal: &Calibration, die_c: f64) -> [f64; 3] {
    cal.temperature.as_ref().map_or([0.0; 3], |th| {
        let b = th.gyro_bias_polynomials();
        let dt = die_c - th.reference_c;
        std::array::from_fn(|i| shared::sensor_models::poly_no_constant(&b[i], dt))
    })
}

/// The state of a simulation running row by row through the plan's segments.
struct RowSimulator<'a> {
    /// The simulated unit.
    cal: &'a Calibration,
    /// Its forward model.
    model: ForwardModel,
    /// The noise model (table errors and the gyro matrix).
    noise: &'a NoiseModel,
    /// Local gravity, m/s².
    gravity_m_s2: f64,
    /// Sample rate, Hz.
    rate: f64,
    /// Sample interval, s.
    dt: f64,
    /// The sensors' noise sources.
    sensors: SensorNoise,
    /// Stream of the mounts' tilts.
    rng_tilt: Rng,
    /// Chamber, die and sensor temperatures.
    temperature: ThermalState,
    /// What was drawn so far.
    summary: SimulationSummary,
    /// Rows produced so far.
    index: u64,
}

impl<'a> RowSimulator<'a> {
    /// A simulation of `plan` on `cal` (checked by [`simulable_model`], whose result is `model`) at
    /// its first row.
    fn new(
        cal: &'a Calibration,
        model: ForwardModel,
        plan: &Plan,
        noise: &'a NoiseModel,
        thermal: &ThermalSim,
        seed: u64,
    ) -> RowSimulator<'a> {
        let rate = plan.sample_rate_hz;
        let dt = 1.0 / rate;
        // Noise in output units, per axis: mg × the axis's scale factor (‖row_i(M)‖).
        let k: [f64; 3] = std::array::from_fn(|i| linalg::norm(&model.m_out_per_g[i]));
        let first_c = plan.segments.iter().find_map(|s| s.temp_c);
        RowSimulator {
            cal,
            model,
            noise,
            gravity_m_s2: plan.gravity_m_s2,
            rate,
            dt,
            sensors: SensorNoise::new(noise, k, dt, seed),
            rng_tilt: Rng::new(seed, STREAM_TILT),
            temperature: ThermalState::new(thermal, first_c, Rng::new(seed, STREAM_TEMPERATURE)),
            summary: SimulationSummary {
                seed,
                rows: 0,
                mount_up_b: BTreeMap::new(),
                mount_tilt_deg: BTreeMap::new(),
                notes: Vec::new(),
            },
            index: 0,
        }
    }

    /// The true up of `seg`'s mount: drawn (tilted, docs/model.md §7) and recorded the first time
    /// the mount is used, the same for every later segment on it.
    fn mount_up(&mut self, seg: &SegmentPlan) -> [f64; 3] {
        let mount = seg.mount_name();
        if let Some(up) = self.summary.mount_up_b.get(&mount) {
            return *up;
        }
        let sigma = self.noise.table_tilt_deg.to_radians();
        let up = if sigma > 0.0 {
            let (n1, n2) = (
                self.rng_tilt.normal() * sigma,
                self.rng_tilt.normal() * sigma,
            );
            self.summary
                .mount_tilt_deg
                .insert(mount.clone(), n1.hypot(n2).to_degrees());
            tilt(seg.up_b, n1, n2)
        } else {
            seg.up_b
        };
        self.summary.mount_up_b.insert(mount, up);
        up
    }

    /// Simulates every row of `seg`, handing each to `sink`; stops at the sink's first error.
    fn segment<E>(
        &mut self,
        seg: &SegmentPlan,
        sink: &mut impl FnMut(&str, f64, &[f64; 3], &[f64; 3], f64) -> Result<(), E>,
    ) -> Result<(), E> {
        let up = self.mount_up(seg);
        let duration = seg.duration_s.unwrap_or(0.0);
        let n = (duration * self.rate).round() as u64;
        let r0 = seg.rate_deg_s;
        let r1 = seg.rate_end_deg_s.unwrap_or(r0);
        let spinning = !seg.is_static();
        let accel_deg_s2 = (r1 - r0) / duration;
        let mut table = TableState {
            up_b: up,
            rate_rad_s: 0.0,
            accel_rad_s2: 0.0,
            centre_m: seg.table_centre_m.unwrap_or([0.0; 3]),
        };
        for j in 0..n {
            let t_local = j as f64 * self.dt;
            if spinning {
                let cmd = r0 + accel_deg_s2 * t_local;
                table.rate_rad_s = (cmd * (1.0 + self.noise.table_rate_scale)
                    + self.noise.table_rate_offset_deg_s)
                    .to_radians();
                table.accel_rad_s2 =
                    (accel_deg_s2 * (1.0 + self.noise.table_rate_scale)).to_radians();
            }
            let (u, w, temp_c) = self.row(seg, &table, t_local);
            let t = self.index as f64 * self.dt;
            sink(&seg.name, t, &u, &w, temp_c)?;
            self.index += 1;
        }
        Ok(())
    }

    /// One row `t_local` into `seg` with the table in `table`'s state: the accelerometer's outputs,
    /// the gyro's rates and the temperature sensor's reading, each with its noise.
    fn row(
        &mut self,
        seg: &SegmentPlan,
        table: &TableState,
        t_local: f64,
    ) -> ([f64; 3], [f64; 3], f64) {
        let motion = table.motion(self.gravity_m_s2);
        let mut u = self.model.outputs(&motion).raw;
        let chamber_c = super::thermal::chamber_c(seg, t_local);
        let (die_c, temp_c) = self.temperature.step(chamber_c, self.dt);
        if let Some(th) = &self.cal.temperature {
            u = super::thermal::outputs_at(th, &self.model.zero_bias_out, &u, die_c);
        }
        self.sensors.add_to_accel(&mut u);
        let mut w = linalg::mat_vec(&self.noise.gyro_matrix, &motion.omega.rad_s);
        // The gyro bias follows the die too (docs/model.md §9).
        self.sensors
            .add_to_gyro(&mut w, &gyro_thermal_bias(self.cal, die_c));
        (u, w, temp_c)
    }
}

/// Simulates `plan` on `unit` into the session directory `dir` (`plan.toml`, `samples.csv`,
/// `truth.toml`). The plan written is `plan` with the unit's output unit (and its unit id when the
/// plan has none), so that the session is self-consistent.
pub fn simulate_to_dir(
    dir: &Path,
    unit: &UnitFile,
    plan: &Plan,
    noise: &NoiseModel,
    seed: u64,
    overwrite: bool,
) -> Result<SimulationSummary, SimulateError> {
    let hidden = indicatif::ProgressBar::hidden();
    simulate_to_dir_with_progress(dir, unit, plan, noise, seed, overwrite, &hidden)
}

/// [`simulate_to_dir`], advancing `bar` by rows (its length is set here).
pub fn simulate_to_dir_with_progress(
    dir: &Path,
    unit: &UnitFile,
    plan: &Plan,
    noise: &NoiseModel,
    seed: u64,
    overwrite: bool,
    bar: &indicatif::ProgressBar,
) -> Result<SimulationSummary, SimulateError> {
    let cal = unit.to_calibration().map_err(SimulateError::Unit)?;
    let mut notes = Vec::new();
    let noise = &simulated_noise(unit, noise);
    let (fitted, normalisation) = cal.statics.to_fitted().map_err(SimulateError::Params)?;
    if normalisation.needs_warning() {
        notes.push(Note::SimNormalised {
            row_norms: normalisation.row_norms,
        });
    }
    let plan = session_plan(plan, unit, cal.statics.output_unit, &mut notes);
    let writer = SessionWriter::create(dir, &plan, overwrite)?;
    let mut summary = write_samples(writer, unit, &cal, &plan, noise, seed, bar)?;
    summary.notes = notes;
    write_truth(dir, unit, cal, &fitted, noise, seed, &summary)?;
    Ok(summary)
}

/// `noise` with the unit's `[gyro]` table as the simulated gyro: its matrix replaces the noise
/// model's, its bias adds to the noise model's.
pub(crate) fn simulated_noise(unit: &UnitFile, noise: &NoiseModel) -> NoiseModel {
    let mut noise = noise.clone();
    if let Some(g) = &unit.gyro {
        noise.gyro_matrix = g.matrix;
        for i in 0..3 {
            noise.gyro_bias_deg_s[i] += g.bias_rad_s[i].to_degrees();
        }
    }
    noise
}

/// The plan to record: `plan` in the unit's output unit `output_unit` (a note says when that
/// changed it), with the unit's id when the plan names none, so that the session is self-consistent.
fn session_plan(
    plan: &Plan,
    unit: &UnitFile,
    output_unit: shared::OutputUnit,
    notes: &mut Vec<Note>,
) -> Plan {
    let mut plan = plan.clone();
    if plan.output_unit != output_unit {
        notes.push(Note::SimOutputUnit {
            plan: plan.output_unit,
            unit: output_unit,
        });
        plan.output_unit = output_unit;
    }
    if plan.unit_id.is_none() {
        plan.unit_id.clone_from(&unit.unit_id);
    }
    plan
}

/// Simulates `plan` on `cal` (with the unit file's thermal model) into `writer`'s samples, advancing
/// `bar` by rows, and finishes the file.
fn write_samples(
    mut writer: SessionWriter,
    unit: &UnitFile,
    cal: &Calibration,
    plan: &Plan,
    noise: &NoiseModel,
    seed: u64,
    bar: &indicatif::ProgressBar,
) -> Result<SimulationSummary, SimulateError> {
    let total: f64 = plan
        .segments
        .iter()
        .map(|s| (s.duration_s.unwrap_or(0.0) * plan.sample_rate_hz).round())
        .sum();
    bar.set_length(total as u64);
    let thermal = ThermalSim::from_unit_file(unit)?;
    let with_temperature = plan.has_temperature();
    let result =
        simulate_rows_with_temperature(cal, plan, noise, &thermal, seed, |seg, t, u, w, temp| {
            if writer.rows() % 65_536 == 0 {
                bar.set_position(writer.rows());
            }
            if with_temperature {
                writer.write_row_with_temperature(seg, t, u, w, temp)
            } else {
                writer.write_row(seg, t, u, w)
            }
        })?;
    bar.finish_and_clear();
    let summary = result?;
    writer.finish()?;
    Ok(summary)
}

/// Writes truth.toml: the unit as simulated (`fitted`, its installation angles normalised), the
/// unit file's other tables, the noise model and what `summary` records was drawn.
fn write_truth(
    dir: &Path,
    unit: &UnitFile,
    cal: Calibration,
    fitted: &shared::FittedStatic,
    noise: &NoiseModel,
    seed: u64,
    summary: &SimulationSummary,
) -> Result<(), SimulateError> {
    let truth_cal = Calibration {
        statics: fitted.to_paper().map_err(SimulateError::Params)?,
        ..cal
    };
    let unit_id = unit.unit_id().map_err(SimulateError::Unit)?;
    let mut truth = UnitFile::from_calibration(&truth_cal, unit_id, None);
    truth.other = unit.other.clone();
    truth.other.insert("noise".into(), to_value(noise));
    let mut sim = toml::Table::new();
    sim.insert("seed".into(), toml::Value::Integer(seed as i64));
    sim.insert("rows".into(), toml::Value::Integer(summary.rows as i64));
    sim.insert("mount_up_b".into(), to_value(&summary.mount_up_b));
    sim.insert("mount_tilt_deg".into(), to_value(&summary.mount_tilt_deg));
    truth
        .other
        .insert("simulation".into(), toml::Value::Table(sim));
    let text = format!(
        "# Written by `host simulate`: the simulated unit (installation angles normalised as the forward\n\
         # model uses them, docs/model.md §4.2), the [noise] model and the seed. `host simulate --unit` reads it.\n{}",
        truth.to_toml()
    );
    let path = dir.join(TRUTH_FILE);
    std::fs::write(&path, text).map_err(|source| RecordingError::Io { path, source })?;
    Ok(())
}

/// [`simulate_to_dir`] for a calibration (no `[noise]` table, no unit id).
pub fn simulate_calibration_to_dir(
    dir: &Path,
    cal: &Calibration,
    plan: &Plan,
    noise: &NoiseModel,
    seed: u64,
) -> Result<SimulationSummary, SimulateError> {
    let unit = UnitFile::from_calibration(cal, None, None);
    simulate_to_dir(dir, &unit, plan, noise, seed, true)
}

/// A TOML value of a plain serialisable value (the types used here always convert).
fn to_value<T: Serialize>(v: &T) -> toml::Value {
    toml::Value::try_from(v).unwrap_or_else(|e| toml::Value::String(e.to_string()))
}

#[cfg(test)]
mod tests {
    use super::*;
    use recording::session::builtin::builtin_plan;
    use recording::session::{read_session, ReadOptions, SAMPLES_FILE};

    fn paper() -> UnitFile {
        UnitFile::paper_unit()
    }

    fn plan(text: &str) -> Plan {
        Plan::parse(&format!(
            "output_unit = \"V\"\nsample_rate_hz = 1000\n{text}"
        ))
        .unwrap()
    }

    /// Rows of a session's samples.csv, parsed.
    fn rows(dir: &Path) -> Vec<(String, [f64; 7])> {
        let text = std::fs::read_to_string(dir.join(SAMPLES_FILE)).unwrap();
        text.lines()
            .skip(1)
            .map(|l| {
                let f: Vec<&str> = l.split(',').collect();
                (
                    f[0].to_string(),
                    std::array::from_fn(|k| f[k + 1].parse().unwrap()),
                )
            })
            .collect()
    }

    #[test]
    fn same_seed_same_bytes_other_seed_other_bytes() {
        let short = builtin_plan("short").unwrap().unwrap();
        let noise = NoiseModel {
            accel_bias_walk_mg_sqrt_s: 0.01,
            table_tilt_deg: 0.01,
            ..NoiseModel::default()
        };
        let run = |seed| {
            let dir = tempfile::tempdir().unwrap();
            simulate_to_dir(dir.path(), &paper(), &short, &noise, seed, false).unwrap();
            let read = |f: &str| std::fs::read(dir.path().join(f)).unwrap();
            (read(SAMPLES_FILE), read(TRUTH_FILE), read("plan.toml"))
        };
        let a = run(7);
        assert_eq!(a, run(7));
        let b = run(8);
        assert_ne!(a.0, b.0);
        assert_eq!(a.2, b.2);
        // The truth file reads back as a unit file with the noise model that was used.
        let truth: UnitFile = toml::from_str(std::str::from_utf8(&a.1).unwrap()).unwrap();
        assert_eq!(NoiseModel::from_unit_file(&truth).unwrap(), Some(noise));
        assert_eq!(truth.other["simulation"]["seed"].as_integer(), Some(7));
    }

    #[test]
    fn the_gyro_reads_its_matrix_times_the_rate_plus_its_bias() {
        // The unit file's [gyro] table is the simulated gyro; its bias adds to the noise model's.
        let p = plan(
            "[[segment]]\nname = \"z+\"\nup_b = [0, 0, 1]\nduration_s = 0.2\n\
             [[segment]]\nname = \"zx 200\"\nup_b = [0.6, 0, 0.8]\nrate_deg_s = 200\nduration_s = 0.2\n",
        );
        let g = gyro_matrix([5e-3, -5e-3, 2e-3], 0.5f64.to_radians());
        let mut unit = paper();
        unit.gyro = Some(crate::unit_file::GyroSection {
            bias_rad_s: [0.01, -0.02, 0.005],
            matrix: g,
            bias_rad_s_1sigma: None,
            matrix_1sigma: None,
        });
        let noise = NoiseModel {
            gyro_bias_deg_s: [0.1, 0.0, 0.0],
            ..NoiseModel::none()
        };
        let dir = tempfile::tempdir().unwrap();
        simulate_to_dir(dir.path(), &unit, &p, &noise, 1, false).unwrap();
        let s = read_session(dir.path(), &ReadOptions { quiet: true }).unwrap();
        let bias = [0.01 + 0.1f64.to_radians(), -0.02, 0.005];
        let rate = 200f64.to_radians();
        let gw = linalg::mat_vec(&g, &[0.6 * rate, 0.0, 0.8 * rate]);
        for i in 0..3 {
            assert!((s.stats[0].mean_w_rad_s[i] - bias[i]).abs() < 1e-12);
            assert!((s.stats[1].mean_w_rad_s[i] - gw[i] - bias[i]).abs() < 1e-9);
        }
    }

    #[test]
    fn measured_noise_matches_the_requested_sigma() {
        let p = plan(
            "[[segment]]\nname = \"z+\"\nup_b = [0, 0, 1]\nduration_s = 20\n\
             [[segment]]\nname = \"z+ 200\"\nup_b = [0, 0, 1]\nrate_deg_s = 200\nduration_s = 5\n",
        );
        let noise = NoiseModel {
            accel_white_mg: 1.0,
            gyro_white_deg_s: 0.05,
            gyro_bias_deg_s: [0.1, -0.2, 0.3],
            table_rate_scale: 1e-3,
            table_rate_offset_deg_s: 0.5,
            ..NoiseModel::default()
        };
        let dir = tempfile::tempdir().unwrap();
        simulate_to_dir(dir.path(), &paper(), &p, &noise, 1, false).unwrap();
        let s = read_session(dir.path(), &ReadOptions { quiet: true }).unwrap();
        let k = paper().to_calibration().unwrap().statics.scale_out_per_g;
        let st = &s.stats[0];
        assert_eq!(st.count, 20_000);
        for i in 0..3 {
            let mg = st.std_u()[i] / k[i] * 1e3;
            assert!((mg - 1.0).abs() < 0.03, "axis {i}: {mg} mg");
            let gyro = st.std_w()[i].to_degrees();
            assert!((gyro - 0.05).abs() < 0.0015, "gyro {i}: {gyro} °/s");
            let bias = st.mean_w_rad_s[i].to_degrees();
            assert!((bias - noise.gyro_bias_deg_s[i]).abs() < 2e-3, "{bias}");
        }
        // The table spins at 200·(1 + 1e-3) + 0.5 °/s; the gyro sees that plus its bias.
        let spin = s.stats[1].mean_w_rad_s[2].to_degrees();
        assert!((spin - (200.2 + 0.5 + 0.3)).abs() < 3e-3, "{spin}");
    }

    #[test]
    fn bias_walk_and_quantisation_have_the_requested_size() {
        let p = plan("[[segment]]\nname = \"x+\"\nup_b = [1, 0, 0]\nduration_s = 20\n");
        let noise = NoiseModel {
            accel_bias_walk_mg_sqrt_s: 0.1,
            ..NoiseModel::none()
        };
        let dir = tempfile::tempdir().unwrap();
        simulate_to_dir(dir.path(), &paper(), &p, &noise, 3, false).unwrap();
        let r = rows(dir.path());
        let k = paper().to_calibration().unwrap().statics.scale_out_per_g;
        for i in 0..3 {
            let d: Vec<f64> = r
                .windows(2)
                .map(|w| w[1].1[1 + i] - w[0].1[1 + i])
                .collect();
            let sd = (d.iter().map(|x| x * x).sum::<f64>() / d.len() as f64).sqrt();
            let want = 0.1e-3 * k[i] * (1e-3f64).sqrt();
            assert!((sd / want - 1.0).abs() < 0.03, "axis {i}: {sd} vs {want}");
        }
        let q = 1e-3;
        let noise = NoiseModel {
            accel_quantum_out: q,
            ..NoiseModel::default()
        };
        simulate_to_dir(dir.path(), &paper(), &p, &noise, 3, true).unwrap();
        let r = rows(dir.path());
        let mut levels = std::collections::BTreeSet::new();
        for (_, v) in &r {
            for u in &v[1..4] {
                assert!(((u / q) - (u / q).round()).abs() < 1e-6, "{u}");
                levels.insert((u / q).round() as i64);
            }
        }
        // 1 mg ≈ 0.4 mV of noise on a 1 mV step: a handful of levels per axis, not one.
        assert!(levels.len() > 6, "{levels:?}");
    }

    /// Each gyro axis walks with its own strength where given per axis (its steps' 1σ `K_i √dt`,
    /// none at 0); the same strength on every axis is the one strength's session byte for byte;
    /// the per-axis strengths go to truth.toml and back, and a model without them writes none.
    #[test]
    fn the_gyro_walk_per_axis_has_the_requested_size() {
        let p = plan("[[segment]]\nname = \"x+\"\nup_b = [1, 0, 0]\nduration_s = 20\n");
        let axes = [0.01, 0.03, 0.0];
        let noise = NoiseModel {
            gyro_bias_walk_per_axis_deg_s_sqrt_s: Some(axes),
            ..NoiseModel::none()
        };
        let dir = tempfile::tempdir().unwrap();
        simulate_to_dir(dir.path(), &paper(), &p, &noise, 3, false).unwrap();
        let r = rows(dir.path());
        for (i, k) in axes.iter().enumerate() {
            let d: Vec<f64> = r
                .windows(2)
                .map(|w| w[1].1[4 + i] - w[0].1[4 + i])
                .collect();
            let sd = (d.iter().map(|x| x * x).sum::<f64>() / d.len() as f64).sqrt();
            let want = k.to_radians() * (1e-3f64).sqrt();
            if *k == 0.0 {
                assert_eq!(sd, 0.0, "axis {i}");
            } else {
                assert!((sd / want - 1.0).abs() < 0.03, "axis {i}: {sd} vs {want}");
            }
        }
        let truth = std::fs::read_to_string(dir.path().join(TRUTH_FILE)).unwrap();
        let truth: UnitFile = toml::from_str(&truth).unwrap();
        assert_eq!(NoiseModel::from_unit_file(&truth).unwrap(), Some(noise));
        let session = |noise: &NoiseModel| {
            let dir = tempfile::tempdir().unwrap();
            simulate_to_dir(dir.path(), &paper(), &p, noise, 4, false).unwrap();
            let read = |f: &str| std::fs::read_to_string(dir.path().join(f)).unwrap();
            (read(SAMPLES_FILE), read(TRUTH_FILE))
        };
        let one = NoiseModel {
            gyro_bias_walk_deg_s_sqrt_s: 0.02,
            ..NoiseModel::default()
        };
        let per_axis = NoiseModel {
            gyro_bias_walk_per_axis_deg_s_sqrt_s: Some([0.02; 3]),
            ..NoiseModel::default()
        };
        let (a, b) = (session(&one), session(&per_axis));
        assert_eq!(a.0, b.0);
        assert!(
            !a.1.contains("per_axis") && b.1.contains("per_axis"),
            "{}",
            a.1
        );
        let bad = NoiseModel {
            gyro_bias_walk_per_axis_deg_s_sqrt_s: Some([0.01, -1.0, 0.0]),
            ..NoiseModel::none()
        };
        let e = bad.validate().unwrap_err().to_string();
        assert!(e.contains("gyro_bias_walk_per_axis_deg_s_sqrt_s"), "{e}");
    }

    #[test]
    fn noise_free_simulation_is_exactly_the_shared_forward_model() {
        let p = plan(
            "[[segment]]\nname = \"y-\"\nup_b = [0, -1, 0]\nduration_s = 0.05\n\
             [[segment]]\nname = \"oblique ramp\"\nup_b = [0.7071067811865475, 0, 0.7071067811865475]\n\
             rate_deg_s = -50\nrate_end_deg_s = 300\nduration_s = 0.2\ntable_centre_m = [0.01, -0.02, 0.003]\n\
             [[segment]]\nname = \"z+ 150\"\nup_b = [0, 0, 1]\nrate_deg_s = 150\nduration_s = 0.1\n",
        );
        let dir = tempfile::tempdir().unwrap();
        let unit = paper();
        let summary =
            simulate_to_dir(dir.path(), &unit, &p, &NoiseModel::none(), 5, false).unwrap();
        assert_eq!(summary.rows, 350);
        let model = ForwardModel::new(&unit.to_calibration().unwrap()).unwrap();
        let r = rows(dir.path());
        let mut start = 0;
        for seg in &p.segments {
            let n = (seg.duration_s.unwrap() * 1000.0).round() as usize;
            let r0 = seg.rate_deg_s;
            let a = (seg.rate_end_deg_s.unwrap_or(r0) - r0) / seg.duration_s.unwrap();
            for j in 0..n {
                let (name, v) = &r[start + j];
                assert_eq!(name, &seg.name);
                let t = j as f64 * 1e-3;
                let table = TableState {
                    up_b: seg.up_b,
                    rate_rad_s: (r0 + a * t).to_radians(),
                    accel_rad_s2: a.to_radians(),
                    centre_m: seg.table_centre_m.unwrap_or([0.0; 3]),
                };
                let m = table.motion(9.80665);
                assert_eq!(v[0], (start + j) as f64 * 1e-3);
                assert_eq!(&v[1..4], &model.outputs(&m).raw[..], "{name} row {j}");
                assert_eq!(&v[4..7], &m.omega.rad_s[..]);
            }
            start += n;
        }
        assert_eq!(start, r.len());
    }

    #[test]
    fn table_tilt_is_drawn_per_mount_and_recorded() {
        let short = builtin_plan("short").unwrap().unwrap();
        let noise = NoiseModel {
            table_tilt_deg: 0.01,
            ..NoiseModel::none()
        };
        let dir = tempfile::tempdir().unwrap();
        let s = simulate_to_dir(dir.path(), &paper(), &short, &noise, 11, false).unwrap();
        // Six mounts (the spins share the "+" mounts with the static segments).
        assert_eq!(s.mount_tilt_deg.len(), 6);
        assert!(s.mount_tilt_deg.values().all(|t| *t > 0.0 && *t < 0.06));
        let st = read_session(dir.path(), &ReadOptions { quiet: true }).unwrap();
        let model = ForwardModel::new(&paper().to_calibration().unwrap()).unwrap();
        let want = model.outputs(&TableState::at_rest(s.mount_up_b["x+"]).motion(9.80665));
        for i in 0..3 {
            assert!((st.stats[0].mean_u[i] - want.raw[i]).abs() < 1e-12);
        }
        // The mount's spin segments turn about the same tilted up: the noise-free gyro reads
        // rate × that up, and the tilt is not along the nominal axis.
        let up = s.mount_up_b["x+"];
        assert!(up[1].abs() + up[2].abs() > 1e-6, "{up:?}");
        for seg in st.stats.iter().filter(|x| x.name.starts_with("x+ ")) {
            let rate: f64 = seg.name[3..].parse::<f64>().unwrap().to_radians();
            for j in 0..3 {
                assert!(
                    (seg.mean_w_rad_s[j] - rate * up[j]).abs() < 1e-12,
                    "{}",
                    seg.name
                );
            }
        }
    }

    #[test]
    fn errors_name_the_problem() {
        let p = plan("[[segment]]\nname = \"x+\"\nup_b = [1, 0, 0]\n");
        let dir = tempfile::tempdir().unwrap();
        let e = simulate_to_dir(dir.path(), &paper(), &p, &NoiseModel::none(), 1, false)
            .unwrap_err()
            .to_string();
        assert!(e.contains("'x+' has no duration_s"), "{e}");
        let bad = NoiseModel {
            accel_white_mg: -1.0,
            ..NoiseModel::default()
        };
        let e = bad.validate().unwrap_err().to_string();
        assert!(e.contains("accel_white_mg"), "{e}");
        let mut unit = paper();
        unit.other.insert(
            "noise".into(),
            toml::Value::Table(toml::from_str("accel_white_mgg = 2").unwrap()),
        );
        let e = shared::chain::Chain(&NoiseModel::from_unit_file(&unit).unwrap_err()).to_string();
        assert!(e.contains("accel_white_mgg"), "{e}");
    }
}

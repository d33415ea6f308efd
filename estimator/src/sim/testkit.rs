//! Test-only generator of segment statistics from a known unit: the noise-free statistics of
//! [`super::synth`] plus the exact distribution of a white-noise mean (Gaussian, σ/√n per axis), with
//! optional table errors (attitude per mount, rate scale) — all seeded.

use super::synth::{self, ActualSegment, SynthNoise};
use super::thermal::{outputs_at, ThermalSim};
use super::{simulate_rows_with_temperature, NoiseModel};
use crate::estimate::{calibrate_session_stats, CalibrationOutcome, EstimateOptions};
use crate::unit_file::UnitFile;
use recording::session::builtin::builtin_plan;
use recording::session::{Package, Plan, SegmentAccumulator, SegmentPlan, SegmentStats};
use shared::forward::{ForwardModel, TableState};
use shared::{Calibration, Compensator, LeverArms, LeverMode, OutputUnit, ReferencePoint};
use shared::{SensorOutputs, StaticParams};

use shared::rng::Rng;

/// Table errors of a simulated session.
#[derive(Clone, Copy, Debug, Default)]
pub struct TableErrors {
    /// 1σ tilt of each mount about each of the two axes perpendicular to its up, degrees (as
    /// `host simulate --tilt-deg`).
    pub attitude_deg: f64,
    /// 1σ relative rate error of each rotating segment.
    pub rate_rel: f64,
    /// Gyro white noise per sample, rad/s (0: a noise-free gyro mean).
    pub gyro_noise_rad_s: f64,
    /// The gyro reads `G ω + b`: `(G, b)`, b in rad/s (`None`: a perfect gyro).
    pub gyro: Option<([[f64; 3]; 3], [f64; 3])>,
    /// The table's rate scale error, common to every rotating segment.
    pub rate_scale: f64,
}

/// Gyro statistics of a perfect gyro turned into those of a gyro reading `G ω + b`.
fn through_gyro(st: &mut SegmentStats, g: &[[f64; 3]; 3], b: &[f64; 3], sg2: f64) {
    use shared::linalg::mat_vec;
    let w = st.mean_w_rad_s;
    let gw = mat_vec(g, &w);
    let id = |i: usize, j: usize| if i == j { sg2 } else { 0.0 };
    let conj = |m: &[[f64; 3]; 3]| -> [[f64; 3]; 3] {
        core::array::from_fn(|i| {
            core::array::from_fn(|j| {
                (0..3)
                    .map(|k| (0..3).map(|l| g[i][k] * m[k][l] * g[j][l]).sum::<f64>())
                    .sum()
            })
        })
    };
    let wwt: [[f64; 3]; 3] =
        core::array::from_fn(|i| core::array::from_fn(|j| st.mean_wwt[i][j] - id(i, j)));
    let cw: [[f64; 3]; 3] =
        core::array::from_fn(|i| core::array::from_fn(|j| st.cov_w[i][j] - id(i, j)));
    let gwwt = conj(&wwt);
    st.mean_wwt = core::array::from_fn(|i| {
        core::array::from_fn(|j| gwwt[i][j] + gw[i] * b[j] + b[i] * gw[j] + b[i] * b[j] + id(i, j))
    });
    let gcw = conj(&cw);
    st.cov_w = core::array::from_fn(|i| core::array::from_fn(|j| gcw[i][j] + id(i, j)));
    st.mean_w_rad_s = core::array::from_fn(|i| gw[i] + b[i]);
    st.wdot_rad_s2 = mat_vec(g, &st.wdot_rad_s2);
}

fn seg(name: &str, up: [f64; 3], rate: f64) -> SegmentPlan {
    SegmentPlan {
        name: name.into(),
        up_b: up,
        rate_deg_s: rate,
        rate_end_deg_s: None,
        duration_s: Some(60.0),
        table_centre_m: None,
        mount: None,
        ..SegmentPlan::default()
    }
}

/// The paper's plan: ±1 g per axis static, 60 s; 100/150/200 °/s about x, y, z with that axis up.
pub fn paper_plan(unit: OutputUnit) -> Plan {
    let mut segments = Vec::new();
    for (a, n) in ["x", "y", "z"].iter().enumerate() {
        for sgn in [1.0, -1.0] {
            let mut up = [0.0; 3];
            up[a] = sgn;
            segments.push(seg(
                &format!("{n}{}", if sgn > 0.0 { "+" } else { "-" }),
                up,
                0.0,
            ));
        }
    }
    for (a, n) in ["x", "y", "z"].iter().enumerate() {
        let mut up = [0.0; 3];
        up[a] = 1.0;
        for r in [100.0, 150.0, 200.0] {
            let mut s = seg(&format!("{n}+ {r}"), up, r);
            s.mount = Some(format!("{n}+"));
            segments.push(s);
        }
    }
    Plan {
        format_version: 2,
        attitude_sigma_deg: Some(0.0),
        table_rate_sigma_ppm: None,
        output_unit: unit,
        sample_rate_hz: 1000.0,
        gravity_m_s2: shared::STANDARD_GRAVITY_M_S2,
        unit_id: None,
        package: Default::default(),
        acc_offset: None,
        segments,
    }
}

/// The paper's plan plus three 45° oblique mounts spun at ±200 °/s and a spin-up per oblique mount.
pub fn better_plan(unit: OutputUnit) -> Plan {
    let mut p = paper_plan(unit);
    let h = std::f64::consts::FRAC_1_SQRT_2;
    for (n, up) in [
        ("xy", [h, h, 0.0]),
        ("yz", [0.0, h, h]),
        ("zx", [h, 0.0, h]),
    ] {
        for r in [200.0, -200.0] {
            p.segments.push(seg(&format!("{n} {r}"), up, r));
        }
        let mut ramp = seg(&format!("{n} ramp"), up, 0.0);
        ramp.rate_deg_s = 20.0;
        ramp.rate_end_deg_s = Some(200.0);
        ramp.duration_s = Some(30.0);
        p.segments.push(ramp);
    }
    p
}

/// The paper's unit.
pub fn paper_unit() -> Calibration {
    shared::params::PAPER_UNIT
}

/// A random digital unit: 4096 LSB/g ± 5 %, biases ±100 LSB, axis tilts up to 2°, lever arms up to 2 cm.
pub fn random_digital_unit(rng: &mut Rng) -> Calibration {
    let mut angles = [[0.0; 3]; 3];
    for i in 0..3 {
        // Tilt axis i by up to 2° in a random direction.
        let tilt = rng.range(0.0, 2.0f64).to_radians();
        let phi = rng.range(0.0, 2.0 * std::f64::consts::PI);
        let (j, k) = ((i + 1) % 3, (i + 2) % 3);
        let mut a = [0.0; 3];
        a[i] = tilt.cos();
        a[j] = tilt.sin() * phi.cos();
        a[k] = tilt.sin() * phi.sin();
        angles[i] = a.map(|c| c.clamp(-1.0, 1.0).acos().to_degrees());
    }
    Calibration {
        statics: StaticParams {
            output_unit: OutputUnit::Lsb,
            zero_bias_out: core::array::from_fn(|_| rng.range(-100.0, 100.0)),
            scale_out_per_g: core::array::from_fn(|_| 4096.0 * rng.range(0.95, 1.05)),
            installation_angles_deg: angles,
        },
        lever_arms: LeverArms {
            r_m: core::array::from_fn(|_| core::array::from_fn(|_| rng.range(-0.02, 0.02))),
        },
        reference: ReferencePoint::TableAxis,
        gravity_m_s2: shared::STANDARD_GRAVITY_M_S2,
        gyro: None,
        temperature: None,
    }
}

/// Noisy statistics of `plan` run on `truth`: each mean gets N(0, σ²/n) per axis.
pub fn noisy_stats(
    plan: &Plan,
    truth: &Calibration,
    noise_out: f64,
    errors: TableErrors,
    rng: &mut Rng,
) -> Vec<SegmentStats> {
    let unit = ForwardModel::new(truth).expect("valid truth");
    let noise = SynthNoise {
        out_1sigma: [noise_out; 3],
        gyro_1sigma_rad_s: errors.gyro_noise_rad_s,
        sample_rate_hz: plan.sample_rate_hz,
    };
    let mut mount_tilts: std::collections::HashMap<String, [f64; 2]> = Default::default();
    plan.segments
        .iter()
        .map(|sp| {
            let mut actual = ActualSegment::from_plan(sp, 60.0);
            if errors.attitude_deg > 0.0 {
                // One tilt per mount, shared by its segments at rest and spinning.
                let sigma = errors.attitude_deg.to_radians();
                let [n1, n2] = *mount_tilts
                    .entry(sp.mount_name())
                    .or_insert_with(|| [sigma * rng.normal(), sigma * rng.normal()]);
                actual.up_b = crate::sim::session::tilt(actual.up_b, n1, n2);
            }
            if !sp.is_static() {
                actual.rate_start_rad_s *= 1.0 + errors.rate_scale;
                actual.rate_end_rad_s *= 1.0 + errors.rate_scale;
            }
            if errors.rate_rel > 0.0 && !sp.is_static() {
                let f = 1.0 + errors.rate_rel * rng.normal();
                actual.rate_start_rad_s *= f;
                actual.rate_end_rad_s *= f;
            }
            let mut st = synth::segment_stats(&sp.name, &actual, &unit, &noise);
            if let Some((g, b)) = &errors.gyro {
                through_gyro(&mut st, g, b, errors.gyro_noise_rad_s.powi(2));
            }
            let n = st.count as f64;
            for i in 0..3 {
                st.mean_u[i] += noise_out / n.sqrt() * rng.normal();
                if errors.gyro_noise_rad_s > 0.0 {
                    st.mean_w_rad_s[i] += errors.gyro_noise_rad_s / n.sqrt() * rng.normal();
                }
            }
            st
        })
        .collect()
}

/// `plan` with the declared attitude prior (`None`: free attitudes as the plan says) and every
/// segment's duration multiplied by `scale`.
pub fn declared(plan: &Plan, sigma_deg: f64, scale: f64) -> Plan {
    let mut p = plan.clone();
    p.format_version = 2;
    p.attitude_sigma_deg = Some(sigma_deg);
    for s in &mut p.segments {
        s.duration_s = s.duration_s.map(|d| d * scale);
    }
    p
}

/// A fixture plan with more mounts: the six faces and six edge diagonals at rest (30 s), a 200 °/s
/// spin on x+, y+ and z+ (30 s), and the four upper cube corners at rest and spun at ±200 °/s (30 s):
/// 16 mounts.
pub fn many_mounts_plan() -> Plan {
    let h = std::f64::consts::FRAC_1_SQRT_2;
    let c = 1.0 / 3f64.sqrt();
    let mut segments = Vec::new();
    let mut add = |name: String, up: [f64; 3], rate: f64| {
        segments.push(SegmentPlan {
            name,
            up_b: up,
            rate_deg_s: rate,
            duration_s: Some(30.0),
            ..SegmentPlan::default()
        });
    };
    let statics: [(&str, [f64; 3]); 12] = [
        ("x+", [1.0, 0.0, 0.0]),
        ("x-", [-1.0, 0.0, 0.0]),
        ("y+", [0.0, 1.0, 0.0]),
        ("y-", [0.0, -1.0, 0.0]),
        ("z+", [0.0, 0.0, 1.0]),
        ("z-", [0.0, 0.0, -1.0]),
        ("xy", [h, h, 0.0]),
        ("x-y", [h, -h, 0.0]),
        ("yz", [0.0, h, h]),
        ("y-z", [0.0, h, -h]),
        ("zx", [h, 0.0, h]),
        ("-zx", [h, 0.0, -h]),
    ];
    for (n, up) in statics {
        add(n.to_string(), up, 0.0);
    }
    for (n, up) in &statics[..6] {
        if up.iter().sum::<f64>() > 0.0 {
            add(format!("{n} 200"), *up, 200.0);
        }
    }
    for (n, up) in [
        ("ppp", [c, c, c]),
        ("mpp", [-c, c, c]),
        ("pmp", [c, -c, c]),
        ("ppm", [c, c, -c]),
    ] {
        add(n.to_string(), up, 0.0);
        add(format!("{n} 200"), up, 200.0);
        add(format!("{n} -200"), up, -200.0);
    }
    Plan {
        format_version: 2,
        output_unit: shared::OutputUnit::Volts,
        sample_rate_hz: 1000.0,
        gravity_m_s2: shared::STANDARD_GRAVITY_M_S2,
        unit_id: None,
        package: Default::default(),
        acc_offset: None,
        attitude_sigma_deg: None,
        table_rate_sigma_ppm: None,
        segments,
    }
}

/// 1 mg per sample in the output unit of the x axis: the paper's noise.
pub fn paper_noise(truth: &Calibration) -> f64 {
    1e-3 * truth.statics.scale_out_per_g[0]
}

/// The paper's unit on `plan` with [`paper_noise`] and a perfect table, seeded.
pub fn clean_session(plan: &Plan, seed: u64) -> (Calibration, Vec<SegmentStats>) {
    let truth = paper_unit();
    let mut rng = Rng::new(seed, 0);
    let stats = noisy_stats(
        plan,
        &truth,
        paper_noise(&truth),
        TableErrors::default(),
        &mut rng,
    );
    (truth, stats)
}

/// `host/units/thermal-mems.toml`: the paper's unit with tempcos of MEMS size (bias 0.25..0.35
/// mg/°C plus a quadratic term, scale 100..150 ppm/°C).
pub(crate) fn hot_unit_file() -> UnitFile {
    toml::from_str(include_str!("../../../host/units/thermal-mems.toml")).unwrap()
}

/// [`hot_unit_file`] as a calibration.
pub fn hot_unit() -> Calibration {
    hot_unit_file().to_calibration().unwrap()
}

/// Six positions (±1 g per axis) at each chamber set-point, `seconds` each.
pub fn soak_plan(temps_c: &[f64], seconds: f64) -> Plan {
    let mut segments = Vec::new();
    for &t in temps_c {
        for (a, n) in ["x", "y", "z"].iter().enumerate() {
            for (sgn, s) in [(1.0, "+"), (-1.0, "-")] {
                let mut up_b = [0.0; 3];
                up_b[a] = sgn;
                segments.push(SegmentPlan {
                    name: format!("{n}{s} @{t}"),
                    up_b,
                    rate_deg_s: 0.0,
                    rate_end_deg_s: None,
                    duration_s: Some(seconds),
                    table_centre_m: None,
                    mount: Some(format!("{n}{s}")),
                    temp_c: Some(t),
                    temp_end_c: None,
                    ..Default::default()
                });
            }
        }
    }
    Plan {
        attitude_sigma_deg: None,
        table_rate_sigma_ppm: None,
        format_version: recording::session::plan::PLAN_FORMAT_VERSION_TEMPERATURE,
        output_unit: OutputUnit::Volts,
        sample_rate_hz: 1000.0,
        gravity_m_s2: shared::STANDARD_GRAVITY_M_S2,
        unit_id: None,
        package: Default::default(),
        acc_offset: None,
        segments,
    }
}

/// Simulates straight into per-segment statistics (what the reader would make of the CSV).
pub fn simulate_stats(
    cal: &Calibration,
    plan: &Plan,
    noise: &NoiseModel,
    thermal: &ThermalSim,
    seed: u64,
) -> Vec<SegmentStats> {
    let mut accs: Vec<SegmentAccumulator> = plan
        .segments
        .iter()
        .map(|s| SegmentAccumulator::new(s.name.clone()))
        .collect();
    let mut current = 0;
    simulate_rows_with_temperature(cal, plan, noise, thermal, seed, |seg, t, u, w, temp| {
        if plan.segments[current].name != seg {
            current = plan.segments.iter().position(|s| s.name == seg).unwrap();
        }
        accs[current].push_with_temperature(t, u, w, temp);
        Ok::<(), ()>(())
    })
    .unwrap()
    .unwrap();
    accs.iter().filter_map(SegmentAccumulator::finish).collect()
}

/// The realistic nuisances: 1 mg white noise, a 16-bit ADC's step on 5 V, a slow bias random walk,
/// a quantised and noisy temperature sensor.
pub fn nuisances() -> NoiseModel {
    NoiseModel {
        accel_quantum_out: 5.0 / 65536.0,
        accel_bias_walk_mg_sqrt_s: 2e-4,
        ..NoiseModel::default()
    }
}

/// Worst error, µg, of `cal` compensating the truth's noise-free outputs at `temp_c` over `ups`.
pub fn worst_error_ug(
    truth: &Calibration,
    cal: &Calibration,
    temp_c: f64,
    ups: &[[f64; 3]],
) -> f64 {
    let model = ForwardModel::new(truth).unwrap();
    let mut comp = Compensator::new(cal, LeverMode::Off).unwrap();
    comp.refresh(temp_c as f32);
    let g = truth.gravity_m_s2;
    ups.iter()
        .map(|up| {
            let n = shared::linalg::norm(up);
            let up = up.map(|v| v / n);
            let motion = TableState {
                up_b: up,
                rate_rad_s: 0.0,
                accel_rad_s2: 0.0,
                centre_m: [0.0; 3],
            }
            .motion(g);
            let mut u = model.outputs(&motion).raw;
            if let Some(th) = &truth.temperature {
                u = outputs_at(th, &model.zero_bias_out, &u, temp_c);
            }
            let f = comp.compensate_static(&SensorOutputs {
                raw: u.map(|v| v as f32),
            });
            let e: Vec<f64> = (0..3).map(|j| f.m_s2[j] as f64 / g - up[j]).collect();
            (e[0] * e[0] + e[1] * e[1] + e[2] * e[2]).sqrt() * 1e6
        })
        .fold(0.0, f64::max)
}

/// Attitudes no plan holds, for held-out checks.
pub const HELD_OUT_UPS: [[f64; 3]; 4] = [
    [1.0, 1.0, 1.0],
    [-1.0, 0.5, -0.3],
    [0.2, -0.9, 0.4],
    [0.6, 0.1, -0.8],
];

/// The MEMS IMU of `host/units/single-package.toml`.
pub fn single_package_unit() -> Calibration {
    let file =
        crate::unit_file::UnitFile::parse(include_str!("../../../host/units/single-package.toml"))
            .expect("the shipped unit parses");
    assert_eq!(file.package(), Package::Single);
    file.to_calibration().expect("a valid unit")
}

/// Consumer MEMS noise: 1.4 mg white (70 µg/√Hz over a 400 Hz band) in 1 LSB steps, 0.06 °/s gyro.
pub fn mems_noise() -> NoiseModel {
    NoiseModel {
        accel_white_mg: 1.4,
        accel_quantum_out: 1.0,
        gyro_white_deg_s: 0.06,
        ..NoiseModel::default()
    }
}

/// The built-in `single-package` plan, fitted as `package`.
pub fn single_package_plan(package: Package) -> Plan {
    let mut p = builtin_plan("single-package").unwrap().unwrap();
    p.package = package;
    p
}

/// Both fits of one simulated session: (one lever arm, nine).
pub fn single_package_fits(
    truth: &Calibration,
    seed: u64,
) -> (CalibrationOutcome, CalibrationOutcome) {
    let stats = simulate_stats(
        truth,
        &single_package_plan(Package::Single),
        &mems_noise(),
        &ThermalSim::default(),
        seed,
    );
    let one = calibrate_session_stats(
        &single_package_plan(Package::Single),
        &stats,
        &EstimateOptions::default(),
    )
    .expect("the one-point fit");
    let nine = calibrate_session_stats(
        &single_package_plan(Package::Separate),
        &stats,
        &EstimateOptions::default(),
    )
    .expect("the nine-component fit");
    (one, nine)
}

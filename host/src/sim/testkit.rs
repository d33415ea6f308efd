//! Test-only generator of segment statistics from a known unit: the noise-free statistics of
//! [`super::synth`] plus the exact distribution of a white-noise mean (Gaussian, σ/√n per axis), with
//! optional table errors (attitude per mount, rate scale) — all seeded.

use super::synth::{self, ActualSegment, SynthNoise};
use crate::session::{OutputUnitName, Plan, SegmentPlan, SegmentStats};
use shared::forward::ForwardModel;
use shared::{Calibration, LeverArms, OutputUnit, ReferencePoint, StaticParams};

/// SplitMix64 with Box–Muller normals.
pub struct Rng(u64, Option<f64>);

impl Rng {
    pub fn new(seed: u64) -> Rng {
        Rng(seed ^ 0x9E37_79B9_7F4A_7C15, None)
    }
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    /// Uniform in (0, 1).
    pub fn uniform(&mut self) -> f64 {
        ((self.next_u64() >> 11) as f64 + 0.5) / (1u64 << 53) as f64
    }
    pub fn range(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.uniform()
    }
    pub fn normal(&mut self) -> f64 {
        if let Some(z) = self.1.take() {
            return z;
        }
        let (u1, u2) = (self.uniform(), self.uniform());
        let r = (-2.0 * u1.ln()).sqrt();
        let a = 2.0 * std::f64::consts::PI * u2;
        self.1 = Some(r * a.sin());
        r * a.cos()
    }
    pub fn unit_vector(&mut self) -> [f64; 3] {
        let v = [self.normal(), self.normal(), self.normal()];
        let n = shared::linalg::norm(&v);
        v.map(|c| c / n)
    }
}

/// Table errors of a simulated session.
#[derive(Clone, Copy, Debug, Default)]
pub struct TableErrors {
    /// 1σ tilt of each mount, degrees (random direction).
    pub attitude_deg: f64,
    /// 1σ relative rate error of each rotating segment.
    pub rate_rel: f64,
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
        temp_c: None,
        temp_end_c: None,
    }
}

/// The paper's plan: ±1 g per axis static, 60 s; 100/150/200 °/s about x, y, z with that axis up.
pub fn paper_plan(unit: OutputUnitName) -> Plan {
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
        format_version: 1,
        output_unit: unit,
        sample_rate_hz: 1000.0,
        gravity_m_s2: shared::STANDARD_GRAVITY_M_S2,
        unit_id: None,
        segments,
    }
}

/// The paper's plan plus three 45° oblique mounts spun at ±200 °/s and a spin-up per oblique mount.
pub fn better_plan(unit: OutputUnitName) -> Plan {
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
    crate::unit_file::UnitFile::paper_unit()
        .to_calibration()
        .expect("the paper unit is valid")
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
        gyro_1sigma_rad_s: 0.0,
        sample_rate_hz: plan.sample_rate_hz,
    };
    let mut mount_tilts: std::collections::HashMap<String, [f64; 3]> = Default::default();
    plan.segments
        .iter()
        .map(|sp| {
            let mut actual = ActualSegment::from_plan(sp, 60.0);
            if errors.attitude_deg > 0.0 {
                // Small rotation of "up" per mount: up' = up + δ × up.
                let delta = *mount_tilts.entry(sp.mount_name()).or_insert_with(|| {
                    let v = rng.unit_vector();
                    let a = errors.attitude_deg.to_radians() * rng.normal();
                    v.map(|c| c * a)
                });
                let c = shared::linalg::cross(&delta, &actual.up_b);
                let up: [f64; 3] = core::array::from_fn(|j| actual.up_b[j] + c[j]);
                let n = shared::linalg::norm(&up);
                actual.up_b = up.map(|v| v / n);
            }
            if errors.rate_rel > 0.0 && !sp.is_static() {
                let f = 1.0 + errors.rate_rel * rng.normal();
                actual.rate_start_rad_s *= f;
                actual.rate_end_rad_s *= f;
            }
            let mut st = synth::segment_stats(&sp.name, &actual, &unit, &noise);
            let n = st.count as f64;
            for i in 0..3 {
                st.mean_u[i] += noise_out / n.sqrt() * rng.normal();
            }
            st
        })
        .collect()
}

//! `host noise` on simulated data with known noise terms, and against `allantools`.

use super::*;
use crate::export::convert;
use allan::overlapping_adev;
use estimator::sim::{simulate_to_dir, NoiseModel};
use estimator::unit_file::UnitFile;
use recording::session::SegmentPlan;
use recording::testkit::SPELLING;
use std::process::Command;

fn still_plan(rate_hz: f64, duration_s: f64) -> Plan {
    Plan {
        attitude_sigma_deg: None,
        table_rate_sigma_ppm: None,
        format_version: recording::session::plan::PLAN_FORMAT_VERSION,
        output_unit: shared::OutputUnit::Volts,
        sample_rate_hz: rate_hz,
        gravity_m_s2: shared::STANDARD_GRAVITY_M_S2,
        unit_id: None,
        package: Default::default(),
        acc_offset: None,
        segments: vec![
            SegmentPlan {
                attitude: Default::default(),
                attitude_sigma_deg: None,
                name: "short".into(),
                up_b: [1.0, 0.0, 0.0],
                rate_deg_s: 0.0,
                rate_end_deg_s: None,
                duration_s: Some(5.0),
                table_centre_m: None,
                mount: None,
                ..Default::default()
            },
            SegmentPlan {
                attitude: Default::default(),
                attitude_sigma_deg: None,
                name: "long".into(),
                up_b: [0.0, 0.0, 1.0],
                rate_deg_s: 0.0,
                rate_end_deg_s: None,
                duration_s: Some(duration_s),
                table_centre_m: None,
                mount: None,
                ..Default::default()
            },
        ],
    }
}

fn noise() -> NoiseModel {
    NoiseModel {
        accel_white_mg: 1.0,
        accel_bias_walk_mg_sqrt_s: 0.02,
        accel_flicker_mg: 0.05,
        gyro_white_deg_s: 0.05,
        gyro_bias_walk_deg_s_sqrt_s: 0.002,
        gyro_flicker_deg_s: 0.005,
        accel_quantum_out: 1e-6,
        ..NoiseModel::none()
    }
}

/// 100 Hz for 2000 s: τ up to 250 s, long enough to see all three terms.
fn simulated(dir: &Path) -> (UnitFile, NoiseReport) {
    let unit = UnitFile::paper_unit();
    simulate_to_dir(dir, &unit, &still_plan(100.0, 2000.0), &noise(), 7, false).unwrap();
    let cal = unit.to_calibration().unwrap();
    let pm = convert(&cal).unwrap().plain;
    let r = analyse(dir, Some(&pm), SPELLING, true).unwrap();
    (unit, r)
}

#[test]
fn recovers_the_simulated_noise_terms() {
    let dir = tempfile::tempdir().unwrap();
    let (_, r) = simulated(dir.path());
    assert_eq!(r.segment, "long");
    assert_eq!(r.samples, 200_000);
    let g = shared::STANDARD_GRAVITY_M_S2;
    let n = noise();
    // Truths in the analysed units: N = σ/√fs, K and B as given.
    let want = [
        (
            1e-3 * g / 10.0,
            n.accel_flicker_mg * 1e-3 * g,
            n.accel_bias_walk_mg_sqrt_s * 1e-3 * g,
        ),
        (
            n.gyro_white_deg_s.to_radians() / 10.0,
            n.gyro_flicker_deg_s.to_radians(),
            n.gyro_bias_walk_deg_s_sqrt_s.to_radians(),
        ),
    ];
    for a in &r.axes {
        let (wn, wb, wk) = if a.axis.starts_with("accel") {
            want[0]
        } else {
            want[1]
        };
        let t = a.terms;
        // White noise is measured at every τ: a few %. Flicker and random walk show only at the
        // longest τ, from a handful of clusters: a factor of two.
        let ratio = |got: Option<f64>, want: f64| got.map_or(f64::NAN, |g| g / want);
        assert!(
            (ratio(t.white_density, wn) - 1.0).abs() < 0.05,
            "{}: N {:?} vs {wn}",
            a.axis,
            t
        );
        assert!(
            (0.5..2.0).contains(&ratio(t.random_walk, wk)),
            "{}: K {:?} vs {wk}",
            a.axis,
            t
        );
        assert!(
            (0.5..2.0).contains(&ratio(t.bias_instability, wb)),
            "{}: B {:?} vs {wb}",
            a.axis,
            t
        );
    }
    // Kalibr's figures are the worst axes, in SI units.
    let k = &r.kalibr;
    assert_eq!(k.update_rate_hz, Some(100.0));
    let worst_n = r.axes[..3]
        .iter()
        .map(|a| a.terms.white_density.unwrap())
        .fold(0.0, f64::max);
    assert_eq!(k.accelerometer_noise_density, Some(worst_n));
    assert!(k.gyroscope_random_walk.is_some());
}

/// The curve against `allantools.oadev` on the same numbers (as written to a file, shortest
/// round-trip text). Run with `-- --nocapture` to see the table; it needs python3 with allantools
/// (`pip install allantools`) and otherwise checks only the hand-computed case of `allan::tests`.
#[test]
fn matches_allantools_oadev_within_2_percent() {
    let probe = Command::new("python3")
        .args(["-c", "import allantools"])
        .output();
    if !probe.is_ok_and(|o| o.status.success()) {
        eprintln!(
            "python3 with allantools not importable: compared with the hand-computed case only"
        );
        let p = overlapping_adev(&[1.0, 3.0, 2.0, 6.0, 4.0], 1.0, &[1, 2]);
        assert!((p[0].adev - 3.125f64.sqrt()).abs() < 1e-12);
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let unit = UnitFile::paper_unit();
    simulate_to_dir(
        dir.path(),
        &unit,
        &still_plan(100.0, 600.0),
        &noise(),
        11,
        false,
    )
    .unwrap();
    let cal = unit.to_calibration().unwrap();
    let pm = convert(&cal).unwrap().plain;
    let r = analyse(dir.path(), Some(&pm), SPELLING, true).unwrap();
    // The same signals, recomputed here and written as text for python.
    let s = collect_session(dir.path(), true).unwrap();
    let mut fmt = ryu::Buffer::new();
    for (j, axis) in [(0usize, "accel_x"), (5, "gyro_z")] {
        let values: Vec<f64> = if j < 3 {
            (0..s.data[0].len())
                .map(|k| {
                    let u = [s.data[0][k], s.data[1][k], s.data[2][k]];
                    let f = shared::linalg::mat_vec(&pm.k_a_g_per_out, &u);
                    (f[j] - pm.nabla_b_g[j]) * pm.gravity_m_s2
                })
                .collect()
        } else {
            s.data[j].clone()
        };
        let path = dir.path().join(format!("{axis}.txt"));
        let text: String = values
            .iter()
            .map(|v| format!("{}\n", fmt.format(*v)))
            .collect();
        std::fs::write(&path, text).unwrap();
        let ours = &r.axes.iter().find(|a| a.axis == axis).unwrap().points;
        let taus: Vec<String> = ours.iter().map(|p| format!("{:e}", p.tau_s)).collect();
        let script = format!(
            "import numpy, allantools\n\
             y = numpy.loadtxt('{}')\n\
             t, ad, ade, ns = allantools.oadev(y, rate=100.0, data_type='freq', taus=[{}])\n\
             print('\\n'.join('%.17g %.17g' % (a, b) for a, b in zip(t, ad)))",
            path.display(),
            taus.join(",")
        );
        let out = Command::new("python3")
            .args(["-c", &script])
            .output()
            .unwrap();
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        let theirs: Vec<(f64, f64)> = String::from_utf8(out.stdout)
            .unwrap()
            .lines()
            .map(|l| {
                let (a, b) = l.split_once(' ').unwrap();
                (a.parse().unwrap(), b.parse().unwrap())
            })
            .collect();
        assert_eq!(
            theirs.len(),
            ours.len(),
            "{axis}: allantools returned other τ"
        );
        eprintln!("{axis}: tau_s  host_noise  allantools  rel_diff");
        let mut worst = 0.0f64;
        for (p, (t, ad)) in ours.iter().zip(&theirs) {
            assert!((p.tau_s - t).abs() < 1e-9 * t);
            let rel = (p.adev - ad).abs() / ad;
            worst = worst.max(rel);
            eprintln!("{axis}: {:.3e} {:.6e} {:.6e} {:.2e}", t, p.adev, ad, rel);
        }
        eprintln!(
            "{axis}: largest relative difference {worst:.2e} over {} τ",
            ours.len()
        );
        assert!(worst < 0.02, "{axis}: {worst}");
    }
}

#[test]
fn a_bare_samples_csv_and_a_missing_still_segment() {
    let dir = tempfile::tempdir().unwrap();
    let unit = UnitFile::paper_unit();
    simulate_to_dir(
        dir.path(),
        &unit,
        &still_plan(200.0, 10.0),
        &noise(),
        3,
        false,
    )
    .unwrap();
    let r = analyse(&dir.path().join(SAMPLES_FILE), None, SPELLING, true).unwrap();
    assert_eq!(r.segment, "long");
    assert!(
        (r.sample_rate_hz - 200.0).abs() < 1e-6,
        "{}",
        r.sample_rate_hz
    );
    assert_eq!(
        r.kalibr.accelerometer_noise_density, None,
        "no calibration: undetermined"
    );
    assert!(r.kalibr.gyroscope_noise_density.is_some());
    // The JSON round trip the Kalibr export reads.
    let p = dir.path().join("noise.json");
    std::fs::write(&p, serde_json::to_string(&r).unwrap()).unwrap();
    assert_eq!(load_kalibr_noise(&p).unwrap(), r.kalibr);
    // A plan without a static segment.
    let mut plan = still_plan(100.0, 1.0);
    for s in &mut plan.segments {
        s.rate_deg_s = 100.0;
    }
    let d2 = tempfile::tempdir().unwrap();
    simulate_to_dir(d2.path(), &unit, &plan, &NoiseModel::none(), 1, false).unwrap();
    let e = analyse(d2.path(), None, SPELLING, true).unwrap_err();
    assert!(e.to_string().contains("no static segment"), "{e}");
}

#[test]
fn a_bare_csv_with_endless_segment_names_is_refused_naming_the_limit() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("samples.csv");
    let mut text = String::from("segment,t_s,u_x,u_y,u_z,w_x,w_y,w_z\n");
    for k in 0..=recording::limits::MAX_SEGMENTS {
        text += &format!("s{k},{k},0,0,0,0,0,0\n");
    }
    std::fs::write(&path, &text).unwrap();
    let e = analyse(&path, None, SPELLING, true)
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("more than 10000 segments") && e.contains(&format!("line {}", 10_002)),
        "{e}"
    );
    // One name fewer is read (and fails only for having no long still run).
    let fewer: String = text
        .lines()
        .take(10_001)
        .map(|l| format!("{l}\n"))
        .collect();
    std::fs::write(&path, fewer).unwrap();
    let e = analyse(&path, None, SPELLING, true)
        .unwrap_err()
        .to_string();
    assert!(e.contains("usable rows"), "{e}");
}

/// On white noise alone the table shows N and says, for B and K, that this recording does not
/// determine them and how long one would have to be.
#[test]
fn the_table_names_what_white_noise_does_not_determine() {
    let rate = 100.0;
    let mut rng = shared::rng::Rng::new(3, 0);
    let y: Vec<f64> = (0..20_000).map(|_| 1e-2 * rng.normal()).collect();
    let points = allan::overlapping_adev(&y, rate, &allan::octave_sizes(y.len()));
    let terms = allan::fit(&points);
    let axis = AxisNoise {
        axis: "gyro_x".into(),
        unit: "rad/s".into(),
        points,
        terms,
    };
    let report = NoiseReport {
        source: "test".into(),
        segment: "still".into(),
        sample_rate_hz: rate,
        samples: y.len() as u64,
        axes: vec![axis],
        kalibr: KalibrNoise::default(),
        warnings: Vec::new(),
        output_unit: None,
    };
    let text = report.render();
    let row = text.lines().find(|l| l.starts_with("gyro_x")).unwrap();
    assert_eq!(row.matches("n.d.").count(), 2, "{text}");
    for term in ["gyro_x B: not determined", "gyro_x K: not determined"] {
        let line = text
            .lines()
            .find(|l| l.contains(term))
            .unwrap_or_else(|| panic!("{text}"));
        assert!(
            line.contains("at least") && line.contains("this one: 200 s"),
            "{text}"
        );
    }
    assert!(!text.contains("gyro_x N: not determined"), "{text}");
}

/// A recording already in m/s² (or g) gives Kalibr's accelerometer figures without a calibration:
/// noise.json says which output unit its raw figures are in: the session's plan's (volts for the
/// paper's unit, whose plan says V), read back from the JSON; a bare samples.csv states none.
#[test]
fn the_report_records_the_recordings_output_unit() {
    let dir = tempfile::tempdir().unwrap();
    let unit = UnitFile::paper_unit();
    simulate_to_dir(
        dir.path(),
        &unit,
        &still_plan(200.0, 10.0),
        &noise(),
        4,
        false,
    )
    .unwrap();
    let r = analyse(dir.path(), None, SPELLING, true).unwrap();
    assert_eq!(r.axes[0].unit, "output unit");
    // Volts need a calibration for Kalibr's figures, and the warning names the option.
    assert!(
        r.warnings
            .iter()
            .any(|w| w.starts_with("no <Calibration>: ")),
        "{:?}",
        r.warnings
    );
    assert_eq!(r.output_unit, Some(OutputUnit::Volts));
    let json = serde_json::to_value(&r).unwrap();
    assert_eq!(json["output_unit"], "V");
    let back: NoiseReport = serde_json::from_value(json).unwrap();
    assert_eq!(back.output_unit, Some(OutputUnit::Volts));
    let bare = analyse(&dir.path().join(SAMPLES_FILE), None, SPELLING, true).unwrap();
    assert_eq!(bare.output_unit, None);
}

/// 1 mg of white noise per sample at 200 Hz is N = 1e-3 g / √200 Hz, in m/s²/√Hz.
#[test]
fn a_recording_in_metres_per_second_squared_needs_no_calibration_for_kalibr() {
    let g = shared::STANDARD_GRAVITY_M_S2;
    let want = 1e-3 * g / 200f64.sqrt();
    for unit in [
        OutputUnit::MetresPerSecondSquared,
        OutputUnit::StandardGravity,
    ] {
        let dir = tempfile::tempdir().unwrap();
        let truth = estimator::sim::handheld::logger_unit(unit);
        let file = UnitFile::from_calibration(&truth, None, None);
        let mut plan = still_plan(200.0, 60.0);
        plan.output_unit = unit;
        let white = NoiseModel {
            accel_white_mg: 1.0,
            ..NoiseModel::none()
        };
        simulate_to_dir(dir.path(), &file, &plan, &white, 5, false).unwrap();
        let r = analyse(dir.path(), None, SPELLING, true).unwrap();
        let n = r.kalibr.accelerometer_noise_density.unwrap();
        assert!(
            (n / want - 1.0).abs() < 0.05,
            "{unit:?}: N {n:e}, want {want:e}"
        );
        assert_eq!(r.axes[0].unit, "m/s^2");
        assert!(
            r.warnings.iter().all(|w| !w.contains("<Calibration>")),
            "{:?}",
            r.warnings
        );
    }
}

/// The figure as engineers draw it: a panel per axis, the measured curve with 1σ bars from the
/// cluster count (25 % at nine clusters, IEEE 952), and each determined term as its own line,
/// labelled with its value: N's line reads N at τ = 1 s on a −½ slope.
#[test]
fn the_allan_figure_has_error_bars_and_a_line_per_term() {
    let dir = tempfile::tempdir().unwrap();
    let unit = UnitFile::paper_unit();
    simulate_to_dir(
        dir.path(),
        &unit,
        &still_plan(200.0, 60.0),
        &noise(),
        9,
        false,
    )
    .unwrap();
    let r = analyse(dir.path(), None, SPELLING, true).unwrap();
    let f = r.figure();
    assert_eq!(f.panels.len(), 6);
    for (panel, axis) in f.panels.iter().zip(&r.axes) {
        let measured = &panel.series[0];
        let bars = measured.error.as_ref().expect("1σ bars");
        for (p, e) in axis.points.iter().zip(bars) {
            let m = (p.tau_s * r.sample_rate_hz).round() as usize;
            let want = p.adev / (2.0 * ((r.samples as usize / m) as f64 - 1.0)).sqrt();
            assert!(
                (e / want - 1.0).abs() < 1e-9,
                "{}: τ {} bar {e} vs {want}",
                axis.axis,
                p.tau_s
            );
        }
        let n = axis.terms.white_density.expect("N determined");
        let line = panel
            .series
            .iter()
            .find(|s| s.label.starts_with("N = "))
            .expect("an N line");
        assert!(line.label.contains(&format!("{n:.3e}")), "{}", line.label);
        let (t0, y0) = line.points[0];
        assert!(
            (y0 * t0.sqrt() / n - 1.0).abs() < 1e-12,
            "N line reads N at τ = 1 s"
        );
        let drawn_terms = panel
            .series
            .iter()
            .filter(|s| s.label.contains(" = "))
            .count();
        let determined = axis.terms.values().iter().filter(|v| v.is_some()).count();
        assert_eq!(drawn_terms, determined, "{}", axis.axis);
        // Every term is in the legend: drawn with its value in units, or said undetermined.
        let unit = panel
            .y_desc
            .trim_start_matches("Allan deviation [")
            .trim_end_matches(']');
        for (name, per) in [("N", "/√Hz ("), ("B", " ("), ("K", "/√s (")] {
            let entry = panel
                .series
                .iter()
                .find(|s| {
                    s.label.starts_with(&format!("{name} "))
                        || s.label.starts_with(&format!("{name}:"))
                })
                .unwrap_or_else(|| panic!("{}: no legend entry for {name}", axis.axis));
            assert!(
                entry.label.contains(&format!(" {unit}{per}"))
                    || entry.label.contains("not determined"),
                "{}: {}",
                axis.axis,
                entry.label
            );
        }
    }
}

//! The `fusion-c` header compiled with gcc against x-io Fusion's model as both of its versions
//! declare it, and run: Fusion's own formula against the truth and against `host apply`.

use super::*;

/// x-io Fusion's types and `FusionModelInertial` as its current FusionMath.h / FusionModel.h define
/// them (row-major `float array[9]`), for compiling the generated header without the library.
const FUSION_STUB: &str = r#"
#ifndef FUSION_H
#define FUSION_H
#define FUSION_MODEL_H
typedef union { float array[3]; struct { float x; float y; float z; } axis; } FusionVector;
typedef union { float array[9]; struct { float xx, xy, xz, yx, yy, yz, zx, zy, zz; } element; } FusionMatrix;
static inline FusionVector FusionVectorSubtract(const FusionVector a, const FusionVector b) {
    const FusionVector r = {.axis = {a.axis.x - b.axis.x, a.axis.y - b.axis.y, a.axis.z - b.axis.z}};
    return r;
}
static inline FusionVector FusionVectorHadamard(const FusionVector a, const FusionVector b) {
    const FusionVector r = {.axis = {a.axis.x * b.axis.x, a.axis.y * b.axis.y, a.axis.z * b.axis.z}};
    return r;
}
static inline FusionVector FusionMatrixMultiply(const FusionMatrix m, const FusionVector v) {
    const FusionVector r = {.axis = {
        m.element.xx * v.axis.x + m.element.xy * v.axis.y + m.element.xz * v.axis.z,
        m.element.yx * v.axis.x + m.element.yy * v.axis.y + m.element.yz * v.axis.z,
        m.element.zx * v.axis.x + m.element.zy * v.axis.y + m.element.zz * v.axis.z}};
    return r;
}
static inline FusionVector FusionModelInertial(const FusionVector uncalibrated, const FusionMatrix misalignment,
                                               const FusionVector sensitivity, const FusionVector offset) {
    return FusionMatrixMultiply(misalignment, FusionVectorHadamard(FusionVectorSubtract(uncalibrated, offset), sensitivity));
}
#endif
"#;

const FUSION_MAIN: &str = r#"
#include <stdio.h>
#include "Fusion.h"
#include "fusion_calibration.h"
int main(void) {
    FusionVector u;
    while (scanf("%f %f %f", &u.array[0], &u.array[1], &u.array[2]) == 3) {
        const FusionVector f = ACAL_FUSION_INERTIAL(u, accelerometerMisalignment, accelerometerSensitivity, accelerometerOffset);
        printf("%.9g %.9g %.9g\n", f.axis.x, f.axis.y, f.axis.z);
    }
    return 0;
}
"#;

#[test]
fn fusion_header_compiles_and_its_model_recovers_the_specific_force() {
    let unit = UnitFile::paper_unit();
    let cal = unit.to_calibration().unwrap();
    let input = ExportInput::for_tests(&unit, cal);
    let text = render_fusion(&input).unwrap();
    assert!(text.contains("Gyroscope: UNDETERMINED"));
    assert!(!text.contains("gyroscopeOffset"));
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("Fusion.h"), FUSION_STUB).unwrap();
    std::fs::write(dir.path().join("fusion_calibration.h"), text).unwrap();
    std::fs::write(dir.path().join("main.c"), FUSION_MAIN).unwrap();
    compile(dir.path(), &["main.c"]);
    let model = ForwardModel::new(&cal).unwrap();
    let g = cal.gravity_m_s2;
    let mut truth = Vec::new();
    let mut stdin = String::new();
    for k in 0..30 {
        let x = f64::from(k);
        let f_g = [(0.3 * x).sin(), (0.7 * x).cos() * 0.9, 0.5 - 0.03 * x];
        let u = model
            .outputs(&BodyMotion {
                f_o: BodySpecificForce {
                    m_s2: f_g.map(|v| v * g),
                },
                omega: BodyRate::default(),
                omega_dot: BodyAngularAccel::default(),
            })
            .raw;
        stdin += &format!("{:e} {:e} {:e}\n", u[0] as f32, u[1] as f32, u[2] as f32);
        truth.push(f_g);
    }
    let out = run(dir.path(), &stdin);
    let rows: Vec<Vec<f64>> = out
        .lines()
        .map(|l| l.split(' ').map(|v| v.parse().unwrap()).collect())
        .collect();
    assert_eq!(rows.len(), truth.len());
    for (r, t) in rows.iter().zip(&truth) {
        for j in 0..3 {
            // f32 inputs of ~2.4 V carry ~0.1 µV of rounding (0.3 µg); f32 arithmetic adds a few more.
            assert!((r[j] - t[j]).abs() < 5e-6, "{r:?} vs {t:?}");
        }
    }
}

const FUSION_GYRO_MAIN: &str = r#"
#include <stdio.h>
#include "Fusion.h"
#include "fusion_calibration.h"
int main(void) {
    FusionVector w;
    while (scanf("%f %f %f", &w.array[0], &w.array[1], &w.array[2]) == 3) {
        const FusionVector omega = ACAL_FUSION_INERTIAL(w, gyroscopeMisalignment, gyroscopeSensitivity, gyroscopeOffset);
        printf("%.9g %.9g %.9g\n", omega.axis.x, omega.axis.y, omega.axis.z);
    }
    return 0;
}
"#;

#[test]
fn fusion_header_with_a_gyro_recovers_the_body_rate() {
    let unit = UnitFile::paper_unit();
    let mut cal = unit.to_calibration().unwrap();
    // A typical MEMS gyro (0.5 % scale, 0.5° misalignment, 0.5 °/s bias) and a temperature model.
    let gyro = firmware::paper_unit::typical_gyro();
    cal.gyro = Some(gyro);
    cal.temperature = Some(firmware::paper_unit::typical_thermal_model());
    let input = ExportInput::for_tests(&unit, cal);
    let text = render_fusion(&input).unwrap();
    assert!(!text.contains("UNDETERMINED"), "{text}");
    assert!(text.contains("NOT HELD by FusionModelInertial: the temperature model"));
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("Fusion.h"), FUSION_STUB).unwrap();
    std::fs::write(dir.path().join("fusion_calibration.h"), text).unwrap();
    std::fs::write(dir.path().join("main.c"), FUSION_GYRO_MAIN).unwrap();
    compile(dir.path(), &["main.c"]);
    // Body rates up to ±300 °/s; the gyro reads w = G·ω + b (docs/model.md §8), fed in °/s.
    let mut truth = Vec::new();
    let mut stdin = String::new();
    for k in 0..40 {
        let x = f64::from(k);
        let omega_rad_s = [
            (0.37 * x).sin() * 5.0,
            (0.61 * x).cos() * 3.0,
            0.2 - 0.13 * x,
        ];
        let w_rad_s: Vec<f64> = (0..3)
            .map(|i| {
                (0..3)
                    .map(|j| gyro.matrix[i][j] * omega_rad_s[j])
                    .sum::<f64>()
                    + gyro.bias_rad_s[i]
            })
            .collect();
        let w_deg_s: Vec<String> = w_rad_s
            .iter()
            .map(|v| format!("{:e}", v.to_degrees() as f32))
            .collect();
        stdin += &(w_deg_s.join(" ") + "\n");
        truth.push(omega_rad_s.map(f64::to_degrees));
    }
    let out = run(dir.path(), &stdin);
    let rows: Vec<Vec<f64>> = out
        .lines()
        .map(|l| l.split(' ').map(|v| v.parse().unwrap()).collect())
        .collect();
    assert_eq!(rows.len(), truth.len());
    let mut worst: f64 = 0.0;
    for (r, t) in rows.iter().zip(&truth) {
        for j in 0..3 {
            worst = worst.max((r[j] - t[j]).abs());
        }
    }
    // f32 inputs of up to ~300 °/s carry ≤ 1.5e-5 °/s of rounding each; the f32 subtraction, product
    // and three-term sum add a few more ulps. The uncorrected gyro is off by up to ~2 °/s here.
    assert!(worst < 1e-4, "worst error {worst} deg/s");
    let uncorrected = truth
        .iter()
        .zip(stdin.lines())
        .map(|(t, l)| {
            let w: Vec<f64> = l.split(' ').map(|v| v.parse().unwrap()).collect();
            (0..3).map(|j| (w[j] - t[j]).abs()).fold(0.0, f64::max)
        })
        .fold(0.0, f64::max);
    assert!(uncorrected > 0.5, "the test gyro must need its correction");
}

/// Fusion before 1.3 (`xioTechnologies/Fusion` `Fusion/FusionCalibration.h`): the same model named
/// `FusionCalibrationInertial`, over `FusionMatrixMultiplyVector` and `FusionVectorHadamardProduct`,
/// and its `FusionMatrix` as 1.2's `Fusion/FusionMath.h` declares it: `float array[3][3]` (a flat
/// nine-value initialiser of it is `-Wmissing-braces`, which `-Werror` refuses).
const FUSION_OLD_STUB: &str = r#"
#ifndef FUSION_H
#define FUSION_H
#define FUSION_CALIBRATION_H
typedef union { float array[3]; struct { float x; float y; float z; } axis; } FusionVector;
typedef union { float array[3][3]; struct { float xx, xy, xz, yx, yy, yz, zx, zy, zz; } element; } FusionMatrix;
static inline FusionVector FusionVectorSubtract(const FusionVector a, const FusionVector b) {
    const FusionVector r = {.axis = {a.axis.x - b.axis.x, a.axis.y - b.axis.y, a.axis.z - b.axis.z}};
    return r;
}
static inline FusionVector FusionVectorHadamardProduct(const FusionVector a, const FusionVector b) {
    const FusionVector r = {.axis = {a.axis.x * b.axis.x, a.axis.y * b.axis.y, a.axis.z * b.axis.z}};
    return r;
}
static inline FusionVector FusionMatrixMultiplyVector(const FusionMatrix m, const FusionVector v) {
    const FusionVector r = {.axis = {
        m.element.xx * v.axis.x + m.element.xy * v.axis.y + m.element.xz * v.axis.z,
        m.element.yx * v.axis.x + m.element.yy * v.axis.y + m.element.yz * v.axis.z,
        m.element.zx * v.axis.x + m.element.zy * v.axis.y + m.element.zz * v.axis.z}};
    return r;
}
static inline FusionVector FusionCalibrationInertial(const FusionVector uncalibrated, const FusionMatrix misalignment,
                                                     const FusionVector sensitivity, const FusionVector offset) {
    return FusionMatrixMultiplyVector(misalignment, FusionVectorHadamardProduct(FusionVectorSubtract(uncalibrated, offset), sensitivity));
}
#endif
"#;

/// Reads `u[3] w[3]` (float bits in hex; w in deg/s) and prints the accelerometer (g) and the
/// gyroscope (deg/s) as Fusion's model gives them.
const FUSION_BOTH_MAIN: &str = r#"
#include <stdio.h>
#include <string.h>
#include "Fusion.h"
#include "fusion_calibration.h"
int main(void) {
    unsigned b[6];
    while (scanf("%x %x %x %x %x %x", &b[0], &b[1], &b[2], &b[3], &b[4], &b[5]) == 6) {
        FusionVector u, w;
        memcpy(u.array, b, sizeof u.array);
        memcpy(w.array, b + 3, sizeof w.array);
        const FusionVector f = ACAL_FUSION_INERTIAL(u, accelerometerMisalignment, accelerometerSensitivity, accelerometerOffset);
        const FusionVector omega = ACAL_FUSION_INERTIAL(w, gyroscopeMisalignment, gyroscopeSensitivity, gyroscopeOffset);
        printf("%.9g %.9g %.9g %.9g %.9g %.9g\n", f.axis.x, f.axis.y, f.axis.z, omega.axis.x, omega.axis.y, omega.axis.z);
    }
    return 0;
}
"#;

/// The fusion-c header compiled against Fusion's model as both versions name it, run on the same raw
/// rows as `host apply`: equal to f32 rounding at rest, the lever terms (which Fusion cannot hold)
/// in rotation; the gyro exactly held.
#[test]
fn fusion_header_in_both_fusion_versions_corrects_like_host_apply_within_what_it_holds() {
    use crate::export::consumer_tests::{reference, segments};
    let mut cal = crate::export::consumer_tests::handheld_unit();
    cal.statics.output_unit = shared::OutputUnit::Volts;
    cal.statics.scale_out_per_g = [0.395, 0.398, 0.400];
    cal.statics.zero_bias_out = [2.405, 2.381, 2.436];
    let unit = UnitFile::from_calibration(&cal, None, None);
    let text = render_fusion(&ExportInput::for_tests(&unit, cal)).unwrap();
    let segs = segments(&cal);
    let want = reference(&cal, &segs);
    let rows: Vec<_> = segs.iter().flatten().collect();
    let stdin: String = rows
        .iter()
        .map(|r| {
            let w = r.w_rad_s.map(|v| (v.to_degrees() as f32).to_bits());
            hex_line(r.u.map(|v| (v as f32).to_bits()).iter().chain(&w))
        })
        .collect();
    let g = cal.gravity_m_s2;
    for stub in [FUSION_STUB, FUSION_OLD_STUB] {
        let dir = tempfile::tempdir().unwrap();
        std::fs::write(dir.path().join("Fusion.h"), stub).unwrap();
        std::fs::write(dir.path().join("fusion_calibration.h"), &text).unwrap();
        std::fs::write(dir.path().join("main.c"), FUSION_BOTH_MAIN).unwrap();
        compile(dir.path(), &["main.c"]);
        let out = run(dir.path(), &stdin);
        let (mut rest_ug, mut spin_ug, mut worst_deg_s) = (0.0f64, 0.0f64, 0.0f64);
        for ((line, r), (f_ref, rate_ref)) in out.lines().zip(&rows).zip(want.iter().flatten()) {
            let v: Vec<f64> = line.split(' ').map(|x| x.parse().unwrap()).collect();
            let w2: f64 = r.omega_rad_s.iter().map(|x| x * x).sum();
            let lever_g = w2 * 0.0095 / g;
            for j in 0..3 {
                let d_g = (v[j] - f64::from(f_ref[j]) / g).abs();
                assert!(d_g <= 1.1 * lever_g + 5e-6, "{d_g} g at {r:?}");
                let ug = if r.omega_rad_s == [0.0; 3] {
                    &mut rest_ug
                } else {
                    &mut spin_ug
                };
                *ug = ug.max(d_g * 1e6);
                let d = (v[3 + j] - f64::from(rate_ref[j]).to_degrees()).abs();
                assert!(d < 1e-4, "{d} deg/s");
                worst_deg_s = worst_deg_s.max(d);
            }
        }
        eprintln!(
            "fusion-c: largest difference from host apply {rest_ug:.1} µg at rest, {spin_ug:.1} µg in \
             rotation, {worst_deg_s:.6} °/s"
        );
        assert_eq!(out.lines().count(), rows.len());
    }
}

/// A gyro entry the plan did not determine (the z spins left out: G's z column) is refused, or
/// written marked with --allow-undetermined.
#[test]
fn fusion_header_refuses_or_marks_undetermined_gyro_entries() {
    let mut cal = UnitFile::paper_unit().to_calibration().unwrap();
    cal.gyro = Some(firmware::paper_unit::typical_gyro());
    let mut unit = UnitFile::from_calibration(&cal, None, None);
    let mut sigma = [[1e-5; 3]; 3];
    // 50 times the threshold: undetermined. (Much larger, it also reaches the other columns of
    // G⁻¹ through the misalignments, and those are marked too.)
    for row in &mut sigma {
        row[2] = 0.05;
    }
    unit.gyro.as_mut().unwrap().matrix_1sigma = Some(sigma);
    let mut input = ExportInput::for_tests(&unit, cal);
    let e = render_fusion(&input).unwrap_err();
    let m = e.to_string();
    assert!(
        m.contains(
            "gyroscopeMisalignment[0][2], gyroscopeMisalignment[1][2], gyroscopeMisalignment[2][2]"
        ) && m.contains("--allow-undetermined"),
        "{m}"
    );
    input.options.allow_undetermined = true;
    let text = render_fusion(&input).unwrap();
    let line = text
        .lines()
        .find(|l| l.contains("FusionMatrix gyroscopeMisalignment"))
        .unwrap();
    let marked: Vec<bool> = line
        .split(", ")
        .map(|item| item.contains("UNDETERMINED"))
        .collect();
    assert_eq!(
        marked,
        [false, false, true, false, false, true, false, false, true],
        "{line}"
    );
    // Determined everywhere: numbers only.
    unit.gyro.as_mut().unwrap().matrix_1sigma = Some([[1e-5; 3]; 3]);
    let input = ExportInput::for_tests(&unit, cal);
    assert!(!render_fusion(&input).unwrap().contains("UNDETERMINED"));
}

/// A `FusionMatrix` is written by its named elements, and an entry that is the rounding of an exact
/// inverse (−6e-17 beside entries of order 1), or any entry below half an `f32` step of its row's
/// largest (2e-8 beside 1: it adds nothing to a `float` product), is written as an exact zero; a
/// small entry that is a value (1e-6 beside 1) is kept.
#[test]
fn fusion_matrix_names_its_elements_and_writes_rounding_as_zero() {
    let m = [1.0f32, -6e-17, 1e-6, 0.0, 0.5, 0.0, 2e-8, 0.0, 1.0];
    let text = fusion_matrix(&m, &[[false; 3]; 3]);
    assert_eq!(
        text,
        "{ .element = {.xx = 1e0f, .xy = 0e0f, .xz = 1e-6f, .yx = 0e0f, .yy = 5e-1f, .yz = 0e0f, \
         .zx = 0e0f, .zy = 0e0f, .zz = 1e0f} }"
    );
}

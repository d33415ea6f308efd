//! The `fusion-c` header compiled with gcc against x-io Fusion's model as both of its versions
//! declare it, and run: Fusion's own formula against the truth and against `host apply`.

use super::*;

/// x-io Fusion 1.3's declarations that the header uses, restated from `xioTechnologies/Fusion` at tag
/// v1.3.2 (the newest; the same from v1.3.0): `Fusion/FusionMath.h` lines 23–31 (`FusionVector`),
/// 51–65 (`FusionMatrix`, row-major `float array[9]` beside `element`), 218 (`FusionVectorSubtract`),
/// 261 (`FusionVectorHadamard`), 481–494 (`FusionMatrixMultiply`, its sums in this order), and
/// `Fusion/FusionModel.h` lines 7 (guard `FUSION_MODEL_H`) and 26 (`FusionModelInertial`). The
/// header checks the types' shapes under `-Werror` as the real ones do (a nested `.array`
/// initialiser fails on both, see `array_initialisers_fail_where_named_elements_build`).
const FUSION_1_3: &str = r#"
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
    std::fs::write(dir.path().join("Fusion.h"), FUSION_1_3).unwrap();
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
    std::fs::write(dir.path().join("Fusion.h"), FUSION_1_3).unwrap();
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

/// x-io Fusion 1.2's declarations that the header uses, restated from `xioTechnologies/Fusion` at tag
/// v1.2.9 (the same from v1.1.0 to v1.2.11): `Fusion/FusionMath.h` lines 23–31 (`FusionVector`),
/// 51–65 (`FusionMatrix`, `float array[3][3]` beside `element`: a flat nine-value initialiser of it is
/// `-Wmissing-braces`, which `-Werror` refuses), 216 (`FusionVectorSubtract`), 255
/// (`FusionVectorHadamardProduct`), 418–427 (`FusionMatrixMultiplyVector`), and
/// `Fusion/FusionCalibration.h` lines 7 (guard `FUSION_CALIBRATION_H`) and 26
/// (`FusionCalibrationInertial`, the same formula as 1.3's `FusionModelInertial`).
const FUSION_1_2: &str = r#"
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
    for stub in [FUSION_1_3, FUSION_1_2] {
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
/// written marked with <AllowUndetermined>.
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
        ) && m.contains("<AllowUndetermined>"),
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

/// The exported header's matrices rewritten as `.array` initialisers, flat (`{9 values}`) or nested
/// (`{{3}, {3}, {3}}`): the forms a writer that ignored one of Fusion's versions would produce.
fn as_array_initialisers(text: &str, nested: bool) -> String {
    let mut out = String::new();
    for line in text.lines() {
        let Some((head, tail)) = line.split_once("{ .element = {") else {
            out += line;
            out += "\n";
            continue;
        };
        let inner = tail
            .strip_suffix("} };")
            .expect("a FusionMatrix initialiser");
        let values: Vec<&str> = inner
            .split(", ")
            .map(|item| item.split(" = ").nth(1).unwrap().split(' ').next().unwrap())
            .collect();
        assert_eq!(values.len(), 9, "{line}");
        let array = if nested {
            let rows: Vec<String> = values
                .chunks(3)
                .map(|r| format!("{{{}}}", r.join(", ")))
                .collect();
            format!("{{{}}}", rows.join(", "))
        } else {
            format!("{{{}}}", values.join(", "))
        };
        out += &format!("{head}{{ .array = {array} }};\n");
    }
    out
}

/// The header's `.element` initialisers build under `-Wall -Wextra -pedantic -Werror` against both
/// Fusion versions' declarations, where each `.array` form fails one of them, with the diagnostics
/// gcc gives against the real headers of v1.2.9 and v1.3.2: a flat `.array` (what the header wrote
/// before) is "missing braces" against 1.2's `float array[3][3]`, a nested one "braces around scalar
/// initializer" against 1.3's `float array[9]`. This also keeps the two restated declarations as
/// strict as the real ones.
#[test]
fn array_initialisers_fail_where_named_elements_build() {
    let cal = crate::export::consumer_tests::handheld_unit();
    let unit = UnitFile::from_calibration(&cal, None, None);
    let named = render_fusion(&ExportInput::for_tests(&unit, cal)).unwrap();
    assert!(
        named.contains("gyroscopeMisalignment = { .element = {"),
        "{named}"
    );
    let flat = as_array_initialisers(&named, false);
    let nested = as_array_initialisers(&named, true);
    assert!(
        flat.contains("accelerometerMisalignment = { .array = {9.9"),
        "{flat}"
    );
    assert!(
        nested.contains("gyroscopeMisalignment = { .array = {{"),
        "{nested}"
    );
    let cases = [
        ("1.2 named", FUSION_1_2, &named, None),
        ("1.3 named", FUSION_1_3, &named, None),
        (
            "1.2 flat",
            FUSION_1_2,
            &flat,
            Some("missing braces around initializer"),
        ),
        ("1.3 flat", FUSION_1_3, &flat, None),
        ("1.2 nested", FUSION_1_2, &nested, None),
        (
            "1.3 nested",
            FUSION_1_3,
            &nested,
            Some("braces around scalar initializer"),
        ),
    ];
    for (what, fusion, header, error) in cases {
        let dir = tempfile::tempdir().unwrap();
        std::fs::write(dir.path().join("Fusion.h"), fusion).unwrap();
        std::fs::write(dir.path().join("fusion_calibration.h"), header).unwrap();
        std::fs::write(dir.path().join("main.c"), FUSION_BOTH_MAIN).unwrap();
        let result = compile_result(dir.path(), &["main.c"]);
        match error {
            None => assert!(result.is_ok(), "{what}: {result:?}"),
            Some(e) => {
                let message = result.expect_err(what);
                assert!(
                    message.contains(e) && message.contains("-Werror"),
                    "{what}: {message}"
                );
            }
        }
    }
}

/// Only entries that are zero to the rounding of their computation are written `0.0f` (at most 8
/// `f64` ulps of the matrix's largest): −6e-17 (`cos(fl(π/2))`, 0.28 ulp), −0 and 8 ulps; 8.5 ulps
/// is kept, and so is every small value that is a value: 1e-6, 2e-8, 1e-12 beside 1 (all below half
/// an `f32` step of 1, which a rule in `float` terms would have zeroed). The threshold scales with
/// the matrix: beside 1e3, 1e-13 is rounding and 1e-11 is kept.
#[test]
fn fusion_matrix_writes_only_rounding_as_zero() {
    let eps = f64::EPSILON;
    let m = [
        [1.0, -6.123233995736766e-17, 8.0 * eps],
        [-0.0, 1.0, 1e-6],
        [2e-8, -1e-12, 8.5 * eps],
    ];
    assert_eq!(
        fusion_matrix(&m, &[[false; 3]; 3]),
        format!(
            "{{ .element = {{.xx = 1e0f, .xy = 0.0f, .xz = 0.0f, .yx = 0.0f, .yy = 1e0f, \
             .yz = 1e-6f, .zx = 2e-8f, .zy = -1e-12f, .zz = {:e}f}} }}",
            (8.5 * eps) as f32
        )
    );
    let big = [[1e3, 1e-13, 1e-11], [0.0, 1e3, 0.0], [0.0, 0.0, -1e3]];
    assert_eq!(
        fusion_matrix(&big, &[[false; 3]; 3]),
        "{ .element = {.xx = 1e3f, .xy = 0.0f, .xz = 1e-11f, .yx = 0.0f, .yy = 1e3f, .yz = 0.0f, \
         .zx = 0.0f, .zy = 0.0f, .zz = -1e3f} }"
    );
}

/// The initialiser values of the `FusionMatrix` named `name` in `text`, by element.
fn matrix_items<'a>(text: &'a str, name: &str) -> Vec<&'a str> {
    let line = text
        .lines()
        .find(|l| l.contains(&format!("FusionMatrix {name} = ")))
        .unwrap_or_else(|| panic!("no {name} in {text}"));
    let inner = line.split_once("{ .element = {").unwrap().1;
    inner
        .trim_end_matches("} };")
        .split(", ")
        .map(|item| item.split(" = ").nth(1).unwrap())
        .collect()
}

/// A unit exactly on the body axes but for a 1 µrad tilt of its y axis towards x, and a gyro whose only
/// cross term is 1e-6: the right angles' ±6e-17 and the inverse's zeros are written `0.0f`, the
/// microradian terms kept, and Fusion's model (both versions) gives `host apply`'s specific force and
/// rate on samples where the microradian terms are most of a component (1e-6 g of a 1 g sample along
/// x, 1e-4 °/s of 100 °/s about y), to a few `f32` roundings of the terms summed.
#[test]
fn fusion_header_keeps_a_microradian_misalignment_and_writes_right_angles_as_zero() {
    let d = 1e-6f64.to_degrees();
    let mut cal = shared::params::PAPER_UNIT;
    cal.statics.output_unit = shared::OutputUnit::StandardGravity;
    cal.statics.scale_out_per_g = [1.0; 3];
    cal.statics.zero_bias_out = [0.0; 3];
    cal.statics.installation_angles_deg =
        [[0.0, 90.0, 90.0], [90.0 - d, d, 90.0], [90.0, 90.0, 0.0]];
    cal.lever_arms.r_m = [[0.0; 3]; 3];
    let gyro = GyroCorrection {
        matrix: [[1.004, 1e-6, 0.0], [0.0, 0.997, 0.0], [0.0, 0.0, 1.001]],
        bias_rad_s: [0.01, -0.02, 0.005],
    };
    cal.gyro = Some(gyro);
    let unit = UnitFile::from_calibration(&cal, None, None);
    let text = render_fusion(&ExportInput::for_tests(&unit, cal)).unwrap();
    // The computation's −6e-17 where A holds 0 (what the header wrote before) is gone.
    let a_inv = crate::export::convert(&cal).unwrap().fusion.misalignment;
    assert!(a_inv[0][1] != 0.0 && a_inv[0][1].abs() < 1e-16, "{a_inv:?}");
    assert!(!text.contains("e-17") && !text.contains("-0e0"), "{text}");
    let accel = matrix_items(&text, "accelerometerMisalignment");
    let gyro_items = matrix_items(&text, "gyroscopeMisalignment");
    let zeros = |items: &[&str]| -> Vec<usize> { (0..9).filter(|&k| items[k] == "0.0f").collect() };
    assert_eq!(zeros(&accel), [1, 2, 5, 6, 7], "{accel:?}");
    assert_eq!(zeros(&gyro_items), [2, 3, 5, 6, 7], "{gyro_items:?}");
    let yx: f32 = accel[3].trim_end_matches('f').parse().unwrap();
    assert!((f64::from(yx) + 1e-6).abs() < 1e-12, "{yx}");
    let xy: f32 = gyro_items[1].trim_end_matches('f').parse().unwrap();
    assert!(
        (f64::from(xy) + 1e-6 / (1.004 * 0.997)).abs() < 1e-12,
        "{xy}"
    );

    let g = cal.gravity_m_s2;
    let samples: [([f32; 3], [f64; 3]); 4] = [
        ([1.0, 0.0, 0.0], [0.0, 100.0, 0.0]),
        ([0.0, 1.0, 0.0], [100.0, 0.0, 0.0]),
        ([0.6, -0.8, 0.0], [0.0, 0.0, -250.0]),
        ([0.48, 0.6, 0.64], [30.0, -40.0, 50.0]),
    ];
    let mut applier =
        crate::apply::Applier::new(&cal, shared::LeverMode::RateAndAcceleration, 1000.0).unwrap();
    let mut stdin = String::new();
    let mut want = Vec::new();
    let g_inv = gyro.checked_inverse().unwrap();
    for (u, omega_deg_s) in samples {
        let omega = omega_deg_s.map(f64::to_radians);
        let w: [f64; 3] = std::array::from_fn(|i| {
            crate::export::linalg::dot(&gyro.matrix[i], &omega) + gyro.bias_rad_s[i]
        });
        let w32 = w.map(|v| v as f32);
        let f = applier.sample(&u, &w32).unwrap();
        let rate = applier.rate_rad_s();
        let w_deg = w.map(|v| (v.to_degrees() as f32).to_bits());
        stdin += &hex_line(u.map(f32::to_bits).iter().chain(&w_deg));
        // Each component's bound: a few f32 roundings of the terms it sums, and what the entries
        // written as 0 contribute on the device (at most 8 f64 ulps of the largest each).
        let bound = |m: &[[f64; 3]; 3], v: &[f64; 3], j: usize| {
            let largest = m.iter().flatten().fold(0.0f64, |a, x| a.max(x.abs()));
            let terms: f64 = (0..3).map(|k| (m[j][k] * v[k]).abs()).sum();
            let sum: f64 = v.iter().map(|x| x.abs()).sum();
            6.0 * f64::from(f32::EPSILON) * terms + 8.0 * f64::EPSILON * largest * sum
        };
        let b_deg = gyro.bias_rad_s.map(f64::to_degrees);
        let w_abs: [f64; 3] = std::array::from_fn(|k| w[k].to_degrees().abs() + b_deg[k].abs());
        for j in 0..3 {
            want.push((f64::from(f[j]) / g, bound(&a_inv, &u.map(f64::from), j)));
        }
        for j in 0..3 {
            want.push((f64::from(rate[j]).to_degrees(), bound(&g_inv, &w_abs, j)));
        }
    }
    for fusion in [FUSION_1_2, FUSION_1_3] {
        let dir = tempfile::tempdir().unwrap();
        std::fs::write(dir.path().join("Fusion.h"), fusion).unwrap();
        std::fs::write(dir.path().join("fusion_calibration.h"), &text).unwrap();
        std::fs::write(dir.path().join("main.c"), FUSION_BOTH_MAIN).unwrap();
        compile(dir.path(), &["main.c"]);
        let out = run(dir.path(), &stdin);
        let got: Vec<f64> = out.split_whitespace().map(|v| v.parse().unwrap()).collect();
        assert_eq!(got.len(), want.len(), "{out}");
        let mut worst: f64 = 0.0;
        for (k, (fusion_v, (apply_v, bound))) in got.iter().zip(&want).enumerate() {
            let d = (fusion_v - apply_v).abs();
            assert!(
                d <= *bound,
                "value {k}: Fusion {fusion_v:e}, host apply {apply_v:e}, bound {bound:e}"
            );
            worst = worst.max(d / bound);
        }
        eprintln!("microradian terms: largest difference {worst:.3} of its bound");
    }
}

//! The C outputs compiled with gcc and run: the decoder against the blob (and corrupted copies), the
//! compensation against the firmware's test vectors bit for bit, Fusion's model against the truth.

use super::*;
use crate::unit_file::UnitFile;
use firmware::testvectors::COMP_CASES;
use shared::forward::{BodyMotion, ForwardModel};
use shared::{BodyAngularAccel, BodyRate, BodySpecificForce};
use std::io::Write as _;
use std::path::Path;
use std::process::{Command, Stdio};

fn compiler() -> &'static str {
    if Command::new("gcc").arg("--version").output().is_ok() {
        "gcc"
    } else {
        "cc"
    }
}

/// Compiles `sources` in `dir` into `dir/prog` with strict flags; panics with gcc's message.
fn compile(dir: &Path, sources: &[&str]) {
    let out = Command::new(compiler())
        .current_dir(dir)
        .args([
            "-std=c99",
            "-O2",
            "-Wall",
            "-Wextra",
            "-pedantic",
            "-Werror",
            "-ffp-contract=off",
        ])
        .args(sources)
        .args(["-lm", "-o", "prog"])
        .output()
        .expect("a C compiler runs");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
}

fn run(dir: &Path, stdin: &str) -> String {
    let mut child = Command::new(dir.join("prog"))
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .spawn()
        .unwrap();
    child
        .stdin
        .take()
        .unwrap()
        .write_all(stdin.as_bytes())
        .unwrap();
    let out = child.wait_with_output().unwrap();
    assert!(out.status.success());
    String::from_utf8(out.stdout).unwrap()
}

const MAIN_C: &str = r#"
#include <stdio.h>
#include <string.h>
#include "calibration.h"

static void print_cal(const char *tag, const struct acal_calibration *c) {
    printf("%s %d %d", tag, c->output_unit, c->reference);
    for (int i = 0; i < 3; i++) printf(" %.17g %.17g", c->zero_bias_out[i], c->scale_out_per_g[i]);
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++) printf(" %.17g %.17g", c->installation_angles_deg[i][j], c->lever_arms_m[i][j]);
    printf(" %.17g %02x%02x\n", c->gravity_m_s2, c->unit_id[0], c->unit_id[11]);
}

int main(void) {
    struct acal_calibration d;
    uint8_t bad[ACAL_BLOB_LEN];
    unsigned u[3], w[3], wd[3];
    printf("decode %d\n", (int)acal_decode(ACAL_BLOB, ACAL_BLOB_LEN, &d));
    print_cal("decoded", &d);
    print_cal("initialiser", &ACAL_CALIBRATION);
    memcpy(bad, ACAL_BLOB, ACAL_BLOB_LEN);
    bad[20] ^= 0x04;
    printf("payload-bit %d\n", (int)acal_decode(bad, ACAL_BLOB_LEN, &d));
    memcpy(bad, ACAL_BLOB, ACAL_BLOB_LEN);
    bad[ACAL_BLOB_LEN - 1] ^= 0x80;
    printf("crc-bit %d\n", (int)acal_decode(bad, ACAL_BLOB_LEN, &d));
    printf("truncated %d\n", (int)acal_decode(ACAL_BLOB, ACAL_BLOB_LEN - 1, &d));
    memcpy(bad, ACAL_BLOB, ACAL_BLOB_LEN);
    bad[0] = 0xFF;
    printf("magic %d\n", (int)acal_decode(bad, ACAL_BLOB_LEN, &d));
    while (scanf("%x %x %x %x %x %x %x %x %x", &u[0], &u[1], &u[2], &w[0], &w[1], &w[2], &wd[0], &wd[1], &wd[2]) == 9) {
        float fu[3], fw[3], fwd[3], s[3], f[3];
        memcpy(fu, u, sizeof fu);
        memcpy(fw, w, sizeof fw);
        memcpy(fwd, wd, sizeof fwd);
        acal_compensate_static(&ACAL_COMPENSATOR, fu, s);
        acal_compensate(&ACAL_COMPENSATOR, fu, fw, fwd, f);
        memcpy(u, s, sizeof u);
        memcpy(w, f, sizeof w);
        printf("out %08x %08x %08x %08x %08x %08x\n", u[0], u[1], u[2], w[0], w[1], w[2]);
    }
    return 0;
}
"#;

fn paper_input_unit() -> UnitFile {
    let mut unit = UnitFile::paper_unit();
    unit.unit_id = Some("a1b2c3d4e5f60718293a4b5c".into());
    unit
}

#[test]
fn c_header_compiles_decodes_rejects_corruption_and_compensates_bit_for_bit() {
    let unit = paper_input_unit();
    // The firmware's own paper unit: the test vectors were computed from it.
    let cal = firmware::paper_unit::calibration();
    let input = ExportInput {
        unit: &unit,
        cal,
        noise: None,
        rostopic: "/imu0",
        driver_scale_m_s2_per_out: None,
    };
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(
        dir.path().join("calibration.h"),
        render_header(&input).unwrap(),
    )
    .unwrap();
    std::fs::write(dir.path().join("acal_blob.h"), DECODER_H).unwrap();
    std::fs::write(dir.path().join("acal_blob.c"), DECODER_C).unwrap();
    std::fs::write(dir.path().join("main.c"), MAIN_C).unwrap();
    compile(dir.path(), &["main.c", "acal_blob.c"]);
    let stdin: String = COMP_CASES
        .iter()
        .map(|c| {
            let v: Vec<String> =
                c.u.iter()
                    .chain(&c.w)
                    .chain(&c.wd)
                    .map(|b| format!("{b:08x}"))
                    .collect();
            v.join(" ") + "\n"
        })
        .collect();
    let out = run(dir.path(), &stdin);
    let line = |tag: &str| {
        out.lines()
            .find(|l| l.split(' ').next() == Some(tag))
            .unwrap_or_else(|| panic!("no '{tag}' in {out}"))
            .to_string()
    };
    assert_eq!(line("decode"), "decode 0");
    // ACAL_CRC_MISMATCH = 5, ACAL_LENGTH_MISMATCH = 4, ACAL_BAD_MAGIC = 2.
    assert_eq!(line("payload-bit"), "payload-bit 5");
    assert_eq!(line("crc-bit"), "crc-bit 5");
    assert_eq!(line("truncated"), "truncated 4");
    assert_eq!(line("magic"), "magic 2");
    // Decoded and initialiser values equal the calibration's exactly (%.17g round-trips f64).
    let s = &cal.statics;
    let mut want = vec![0.0, 0.0];
    for i in 0..3 {
        want.extend([s.zero_bias_out[i], s.scale_out_per_g[i]]);
    }
    for i in 0..3 {
        for j in 0..3 {
            want.extend([s.installation_angles_deg[i][j], cal.lever_arms.r_m[i][j]]);
        }
    }
    want.push(cal.gravity_m_s2);
    for tag in ["decoded", "initialiser"] {
        let l = line(tag);
        let f: Vec<&str> = l.split(' ').skip(1).collect();
        let got: Vec<f64> = f[..f.len() - 1]
            .iter()
            .map(|x| x.parse().unwrap())
            .collect();
        assert_eq!(got, want, "{tag}");
        assert_eq!(f[f.len() - 1], "a15c", "{tag}: unit id bytes");
    }
    // The compensation, bit for bit with the firmware's vectors (static and full modes).
    let outs: Vec<&str> = out.lines().filter(|l| l.starts_with("out ")).collect();
    assert_eq!(outs.len(), COMP_CASES.len());
    for (c, l) in COMP_CASES.iter().zip(outs) {
        let bits: Vec<u32> = l
            .split(' ')
            .skip(1)
            .map(|h| u32::from_str_radix(h, 16).unwrap())
            .collect();
        assert_eq!(&bits[..3], &c.out_static, "static");
        assert_eq!(&bits[3..], &c.out_full, "full");
    }
}

#[test]
fn c_header_needs_a_unit_id() {
    let unit = UnitFile::paper_unit();
    let input = ExportInput {
        unit: &unit,
        cal: unit.to_calibration().unwrap(),
        noise: None,
        rostopic: "/imu0",
        driver_scale_m_s2_per_out: None,
    };
    let e = render_header(&input).unwrap_err();
    assert!(e.to_string().contains("unit_id"), "{e}");
}

/// x-io Fusion's types and `FusionModelInertial` as its current FusionMath.h / FusionModel.h define
/// them (row-major `float array[9]`), for compiling the generated header without the library.
const FUSION_STUB: &str = r#"
#ifndef FUSION_H
#define FUSION_H
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
        const FusionVector f = FusionModelInertial(u, accelerometerMisalignment, accelerometerSensitivity, accelerometerOffset);
        printf("%.9g %.9g %.9g\n", f.axis.x, f.axis.y, f.axis.z);
    }
    return 0;
}
"#;

#[test]
fn fusion_header_compiles_and_its_model_recovers_the_specific_force() {
    let unit = UnitFile::paper_unit();
    let cal = unit.to_calibration().unwrap();
    let input = ExportInput {
        unit: &unit,
        cal,
        noise: None,
        rostopic: "/imu0",
        driver_scale_m_s2_per_out: None,
    };
    let text = render_fusion(&input).unwrap();
    assert!(text.contains("Gyroscope: UNDETERMINED"));
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

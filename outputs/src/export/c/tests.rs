//! The C outputs compiled with gcc and run: the decoder against the blob (and corrupted copies), the
//! compensation against the firmware's test vectors bit for bit, Fusion's model against the truth.

use super::*;
use estimator::unit_file::UnitFile;
use firmware::testvectors::{imperfect_unit, COMP_CASES, GYRO_TEMP_CASES};
use shared::blob::ParameterBlob;
use shared::forward::{BodyMotion, ForwardModel};
use shared::{BodyAngularAccel, BodyRate, BodySpecificForce};
use shared::{Calibration, GyroCorrection, ReferencePoint, UnitId};
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
    if let Err(message) = compile_result(dir, sources) {
        panic!("{message}");
    }
}

/// [`compile`]'s build: `-std=c99 -O2 -Wall -Wextra -pedantic -Werror -ffp-contract=off`, gcc's
/// message when it fails.
fn compile_result(dir: &Path, sources: &[&str]) -> Result<(), String> {
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
    if out.status.success() {
        Ok(())
    } else {
        Err(String::from_utf8_lossy(&out.stderr).into_owned())
    }
}

/// Writes the C package of `input` into `dir`, as `host export --format c --out DIR` does.
fn write_package(dir: &Path, input: &ExportInput<'_>) {
    for (name, text) in package(input).unwrap() {
        std::fs::write(dir.join(name), text).unwrap();
    }
}

/// One input line for the C programs: the values as float bits in hex.
fn hex_line<'a>(bits: impl IntoIterator<Item = &'a u32>) -> String {
    let v: Vec<String> = bits.into_iter().map(|b| format!("{b:08x}")).collect();
    v.join(" ") + "\n"
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

/// Prints every field of a `struct acal_calibration`: the integers, then the doubles (`%.17g`
/// round-trips an f64) in the order of [`expected_fields`].
const PRINT_CAL_C: &str = r#"
#include <stdio.h>
#include "acal_blob.h"
static void print_doubles(const double *v, int n) {
    for (int i = 0; i < n; i++) printf(" %.17g", v[i]);
}
static void print_cal(const char *tag, const struct acal_calibration *c) {
    const struct acal_temperature *t = &c->temperature;
    printf("%s %d %d %d %d %d %llu ", tag, c->output_unit, c->reference, c->has_gyro, c->has_temperature,
           t->has_gyro_bias_per_c, (unsigned long long)c->created_unix_s);
    for (int i = 0; i < 12; i++) printf("%02x", c->unit_id[i]);
    print_doubles(c->zero_bias_out, 3);
    print_doubles(c->scale_out_per_g, 3);
    print_doubles(&c->installation_angles_deg[0][0], 9);
    print_doubles(&c->lever_arms_m[0][0], 9);
    print_doubles(c->reference_offset_m, 3);
    print_doubles(&c->gravity_m_s2, 1);
    print_doubles(&c->gyro.matrix[0][0], 9);
    print_doubles(c->gyro.bias_rad_s, 3);
    print_doubles(&t->reference_c, 1);
    print_doubles(t->valid_range_c, 2);
    print_doubles(&t->zero_bias_out_per_c[0][0], 9);
    print_doubles(&t->scale_rel_per_c[0][0], 9);
    print_doubles(&t->gyro_bias_rad_s_per_c[0][0], 9);
    printf("\n");
}
"#;

/// What `print_cal` prints for `cal`, following `acal_blob.h`: an absent gyro is `G = I`, `b = 0`, an
/// absent temperature model zeros. Built from the Rust values, field by field.
fn expected_fields(cal: &Calibration, unit: UnitId, created_unix_s: u64) -> String {
    let s = &cal.statics;
    let (reference, offset) = match cal.reference {
        ReferencePoint::TableAxis => (0, [0.0; 3]),
        ReferencePoint::Centroid => (1, [0.0; 3]),
        ReferencePoint::BodyPoint { offset_m } => (2, offset_m),
    };
    let gyro = cal.gyro.unwrap_or(GyroCorrection::PERFECT);
    let t = cal.temperature;
    let zeros = [[0.0; 3]; 3];
    let mut v: Vec<f64> = Vec::new();
    v.extend(s.zero_bias_out);
    v.extend(s.scale_out_per_g);
    v.extend(s.installation_angles_deg.iter().flatten());
    v.extend(cal.lever_arms.r_m.iter().flatten());
    v.extend(offset);
    v.push(cal.gravity_m_s2);
    v.extend(gyro.matrix.iter().flatten());
    v.extend(gyro.bias_rad_s);
    v.push(t.map_or(0.0, |t| t.reference_c));
    v.extend(t.map_or([0.0; 2], |t| t.valid_range_c));
    v.extend(t.map_or(zeros, |t| t.zero_bias_out_per_c).iter().flatten());
    v.extend(t.map_or(zeros, |t| t.scale_rel_per_c).iter().flatten());
    v.extend(
        t.map_or(zeros, |t| t.gyro_bias_polynomials())
            .iter()
            .flatten(),
    );
    let unit_index = s.output_unit as u8;
    let flags = [
        u8::from(cal.gyro.is_some()),
        u8::from(t.is_some()),
        u8::from(t.is_some_and(|t| t.gyro_bias_rad_s_per_c.is_some())),
    ];
    let doubles: Vec<String> = v.iter().map(|x| format!("{x:e}")).collect();
    format!(
        "{unit_index} {reference} {} {} {} {created_unix_s} {unit} {}",
        flags[0],
        flags[1],
        flags[2],
        doubles.join(" ")
    )
}

/// Normalises a `print_cal` line (after its tag) to [`expected_fields`]' form: the doubles parsed
/// (exact, `%.17g` round-trips) and re-printed in Rust's shortest form.
fn normalised(line: &str) -> String {
    let f: Vec<&str> = line.split(' ').skip(1).collect();
    let doubles: Vec<String> = f[7..]
        .iter()
        .map(|x| format!("{:e}", x.parse::<f64>().unwrap()))
        .collect();
    format!("{} {}", f[..7].join(" "), doubles.join(" "))
}

const MAIN_C: &str = r#"
#include <string.h>
#include "acal_calibration.h"

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
    let input = ExportInput::for_tests(&unit, cal);
    let dir = tempfile::tempdir().unwrap();
    write_package(dir.path(), &input);
    std::fs::write(dir.path().join("main.c"), format!("{PRINT_CAL_C}{MAIN_C}")).unwrap();
    compile(dir.path(), &["main.c", "acal_blob.c", "acal_device.c"]);
    let stdin: String = COMP_CASES
        .iter()
        .map(|c| hex_line(c.u.iter().chain(&c.w).chain(&c.wd)))
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
    // Decoded and initialiser values equal the calibration's exactly (%.17g round-trips f64); the
    // absent sections read as a perfect gyro and no temperature model.
    let unit_id = UnitId::parse_hex("a1b2c3d4e5f60718293a4b5c").unwrap();
    let want = expected_fields(&cal, unit_id, 0);
    assert!(want.starts_with("0 0 0 0 0 0 a1b2c3d4e5f60718293a4b5c "));
    for tag in ["decoded", "initialiser"] {
        assert_eq!(normalised(&line(tag)), want, "{tag}");
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

/// Reads `temp u[3] w[3] wd[3]` (float bits in hex) per line: refreshes a copy of ACAL_COMPENSATOR at
/// `temp`, corrects `w` and compensates; prints the state, the rate and the specific force.
const REFRESH_MAIN_C: &str = r#"
#include <stdio.h>
#include <string.h>
#include "acal_calibration.h"

int main(void) {
    struct acal_compensator c = ACAL_COMPENSATOR;
    unsigned t, u[3], w[3], wd[3];
    while (scanf("%x %x %x %x %x %x %x %x %x %x", &t, &u[0], &u[1], &u[2], &w[0], &w[1], &w[2],
                 &wd[0], &wd[1], &wd[2]) == 10) {
        float ft, fu[3], fw[3], fwd[3], rate[3], f[3];
        unsigned br[3], bf[3];
        int state;
        memcpy(&ft, &t, sizeof ft);
        memcpy(fu, u, sizeof fu);
        memcpy(fw, w, sizeof fw);
        memcpy(fwd, wd, sizeof fwd);
        state = (int)acal_refresh(&c, &ACAL_THERMAL, ft);
        acal_correct_rate(&c, fw, rate);
        acal_compensate(&c, fu, rate, fwd, f);
        memcpy(br, rate, sizeof br);
        memcpy(bf, f, sizeof bf);
        printf("out %d %08x %08x %08x %08x %08x %08x\n", state, br[0], br[1], br[2], bf[0], bf[1], bf[2]);
    }
    return 0;
}
"#;

#[test]
fn c_header_refreshes_with_temperature_and_corrects_the_gyro_bit_for_bit() {
    let unit = paper_input_unit();
    // The firmware's imperfect unit (typical gyro and thermal model): the vectors were computed from it.
    let cal = imperfect_unit();
    let input = ExportInput::for_tests(&unit, cal);
    let header = render_header(&input).unwrap();
    assert!(header.contains("ACAL_THERMAL") && header.contains(".gyro_corrected = 1"));
    let dir = tempfile::tempdir().unwrap();
    write_package(dir.path(), &input);
    std::fs::write(dir.path().join("main.c"), REFRESH_MAIN_C).unwrap();
    compile(dir.path(), &["main.c", "acal_blob.c", "acal_device.c"]);
    let stdin: String = GYRO_TEMP_CASES
        .iter()
        .map(|c| {
            hex_line(
                std::iter::once(&c.temp_c)
                    .chain(&c.u)
                    .chain(&c.w)
                    .chain(&c.wd),
            )
        })
        .collect();
    let out = run(dir.path(), &stdin);
    let outs: Vec<&str> = out.lines().filter(|l| l.starts_with("out ")).collect();
    assert_eq!(outs.len(), GYRO_TEMP_CASES.len());
    let (lo, hi) = (-20.0, 60.0);
    for (c, l) in GYRO_TEMP_CASES.iter().zip(outs) {
        let f: Vec<&str> = l.split(' ').skip(1).collect();
        let temp = f32::from_bits(c.temp_c);
        // 0 in range, 1 clamped (acal_temperature_state), as the device reports it.
        let want_state = if (lo..=hi).contains(&temp) { "0" } else { "1" };
        assert_eq!(f[0], want_state, "{temp} °C");
        let bits: Vec<u32> = f[1..]
            .iter()
            .map(|h| u32::from_str_radix(h, 16).unwrap())
            .collect();
        assert_eq!(&bits[..3], &c.rate, "rate at {temp} °C");
        assert_eq!(&bits[3..], &c.out_full, "full at {temp} °C");
    }
}

/// Blobs written by the version 1 encoder, kept byte for byte in `shared`.
mod v1 {
    include!("../../../../shared/src/blob_v1_vectors.rs");
}

/// Reads one blob per line in hex and prints `rc N` and, when it decodes, its fields. A line
/// `sweep HEX` decodes every truncation and every single-bit flip of the blob and prints how many were
/// accepted.
const DECODE_MAIN_C: &str = r#"
#include <stdlib.h>
#include <string.h>
static size_t parse_hex(const char *s, uint8_t *out, size_t cap) {
    size_t n = 0;
    while (s[0] && s[1] && n < cap) {
        char b[3] = {s[0], s[1], 0};
        out[n++] = (uint8_t)strtoul(b, NULL, 16);
        s += 2;
    }
    return n;
}
int main(void) {
    static char text[8192];
    static uint8_t blob[4096];
    struct acal_calibration d;
    while (scanf("%8191s", text) == 1) {
        if (strcmp(text, "sweep") == 0) {
            size_t n, accepted = 0;
            if (scanf("%8191s", text) != 1) return 1;
            n = parse_hex(text, blob, sizeof blob);
            for (size_t cut = 0; cut < n; cut++) accepted += acal_decode(blob, cut, &d) == ACAL_OK;
            for (size_t i = 0; i < n; i++) {
                for (int bit = 0; bit < 8; bit++) {
                    blob[i] ^= (uint8_t)(1u << bit);
                    accepted += acal_decode(blob, n, &d) == ACAL_OK;
                    blob[i] ^= (uint8_t)(1u << bit);
                }
            }
            printf("sweep %zu %zu\n", n, accepted);
            continue;
        }
        {
            const size_t n = parse_hex(text, blob, sizeof blob);
            const int rc = (int)acal_decode(blob, n, &d);
            printf("rc %d\n", rc);
            if (rc == 0) print_cal("cal", &d);
        }
    }
    return 0;
}
"#;

fn hex(bytes: &[u8]) -> String {
    bytes.iter().map(|b| format!("{b:02x}")).collect()
}

/// A blob around `payload` with header `version`, its length and a correct CRC (as any writer, buggy
/// or not, would sign it).
fn signed(version: u16, payload: &[u8]) -> Vec<u8> {
    let mut v = b"ACAL".to_vec();
    v.extend(version.to_le_bytes());
    v.extend((payload.len() as u16).to_le_bytes());
    v.extend(payload);
    let crc = crc::Crc::<u32>::new(&crc::CRC_32_ISO_HDLC).checksum(&v);
    v.extend(crc.to_le_bytes());
    v
}

fn le_f64s<'a>(v: impl IntoIterator<Item = &'a f64>) -> Vec<u8> {
    v.into_iter().flat_map(|x| x.to_le_bytes()).collect()
}

/// Decodes each blob with the C decoder; returns one `rc` line per blob, followed by its fields
/// normalised when it decodes.
fn c_decode(dir: &Path, blobs: &[Vec<u8>]) -> Vec<String> {
    let stdin: String = blobs.iter().map(|b| hex(b) + "\n").collect();
    let out = run(dir, &stdin);
    let mut lines = out.lines().peekable();
    let mut results = Vec::new();
    while let Some(rc) = lines.next() {
        let mut r = rc.to_string();
        if rc == "rc 0" {
            r += " ";
            r += &normalised(lines.next().unwrap());
        }
        results.push(r);
    }
    assert_eq!(results.len(), blobs.len(), "{out}");
    results
}

#[test]
fn c_decoder_reads_version_2_sections_and_version_1_exactly_and_refuses_the_rest() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("acal_blob.h"), DECODER_H).unwrap();
    std::fs::write(dir.path().join("acal_blob.c"), DECODER_C).unwrap();
    std::fs::write(
        dir.path().join("main.c"),
        format!("{PRINT_CAL_C}{DECODE_MAIN_C}"),
    )
    .unwrap();
    compile(dir.path(), &["main.c", "acal_blob.c"]);
    let unit = UnitId(*b"C-DECODER-V2");
    let gyro = firmware::paper_unit::typical_gyro();
    let thermal = firmware::paper_unit::typical_thermal_model();
    let mut no_gyro_drift = thermal;
    no_gyro_drift.gyro_bias_rad_s_per_c = None;
    // Version 2 blobs from the Rust encoder: both sections, each alone, the inner Option absent.
    let mut cases = Vec::new();
    for (g, t, reference) in [
        (Some(gyro), Some(thermal), ReferencePoint::TableAxis),
        (Some(gyro), None, ReferencePoint::Centroid),
        (
            None,
            Some(no_gyro_drift),
            ReferencePoint::BodyPoint {
                offset_m: [0.01, -0.02, 0.003],
            },
        ),
        (None, None, ReferencePoint::TableAxis),
    ] {
        let mut cal = firmware::paper_unit::calibration();
        cal.gyro = g;
        cal.temperature = t;
        cal.reference = reference;
        let blob = ParameterBlob {
            unit_id: unit,
            calibration: cal,
            created_unix_s: 1_790_000_123,
        };
        let (buf, n) = blob.to_bytes().unwrap();
        assert_eq!(u16::from_le_bytes([buf[4], buf[5]]), 2);
        cases.push((
            buf[..n].to_vec(),
            expected_fields(&cal, unit, 1_790_000_123),
        ));
    }
    // Version 1 blobs (the old encoder's bytes): the paper unit, and LSB with a body point.
    let v1_unit = UnitId(*b"V1-BLOB-UNIT");
    cases.push((
        v1::V1_PAPER.to_vec(),
        expected_fields(&shared::params::PAPER_UNIT, v1_unit, 1_790_000_000),
    ));
    let mut lsb = shared::params::PAPER_UNIT;
    lsb.statics.output_unit = shared::OutputUnit::Lsb;
    lsb.reference = ReferencePoint::BodyPoint {
        offset_m: [0.01, -0.02, 0.003],
    };
    cases.push((
        v1::V1_LSB_BODY_POINT.to_vec(),
        expected_fields(&lsb, v1_unit, 1_790_000_000),
    ));
    // Version 2 built by hand from the version 1 payload, postcard's encoding spelled out: both
    // Options absent (0, 0); a gyro section (1, 12 f64 LE) and no temperature model (0).
    let v1_payload = &v1::V1_PAPER[8..v1::V1_PAPER.len() - 4];
    let absent = [v1_payload, &[0, 0]].concat();
    cases.push((
        signed(2, &absent),
        expected_fields(&shared::params::PAPER_UNIT, v1_unit, 1_790_000_000),
    ));
    let gyro_bytes = le_f64s(gyro.matrix.iter().flatten().chain(&gyro.bias_rad_s));
    let with_gyro = [v1_payload, &[1], &gyro_bytes, &[0]].concat();
    let mut paper_gyro = shared::params::PAPER_UNIT;
    paper_gyro.gyro = Some(gyro);
    cases.push((
        signed(2, &with_gyro),
        expected_fields(&paper_gyro, v1_unit, 1_790_000_000),
    ));
    let blobs: Vec<Vec<u8>> = cases.iter().map(|(b, _)| b.clone()).collect();
    let got = c_decode(dir.path(), &blobs);
    for ((blob, want), got) in cases.iter().zip(&got) {
        // The Rust decoder reads the same blob as the same calibration (independent of the C).
        let rust = shared::blob::decode(blob).unwrap();
        assert_eq!(
            expected_fields(&rust.calibration, rust.unit_id, rust.created_unix_s),
            *want
        );
        assert_eq!(*got, format!("rc 0 {want}"));
    }

    // Refused, each with its layer's error, where the Rust decoder refuses too.
    // ACAL_UNSUPPORTED_VERSION = 3, ACAL_CRC_MISMATCH = 5, ACAL_MALFORMED = 6, ACAL_NON_FINITE = 7.
    let full = &cases[0].0;
    let full_payload = &full[8..full.len() - 4];
    let mut v3 = full.clone();
    v3[4] = 3;
    let mut v0 = full.clone();
    v0[4] = 0;
    let mut v1_header = full.clone();
    v1_header[4] = 1;
    let mut nan_gyro = with_gyro.clone();
    let at = v1_payload.len() + 1 + 8 * 9;
    nan_gyro[at..at + 8].copy_from_slice(&f64::NAN.to_le_bytes());
    // The output unit's variant (a u32 varint, one byte 0x00 here) respelled: 6 bytes, or 5 whose last
    // carries bits beyond 32. Postcard refuses both.
    let respelled_unit =
        |varint: &[u8]| [&v1_payload[..12], varint, &v1_payload[13..], &[0, 0]].concat();
    assert_eq!(v1_payload[12], 0);
    // The creation time (a u64 varint, the payload's last 5 bytes) as 10 bytes whose last carries a
    // bit beyond 64.
    let created_at = v1_payload.len() - 5;
    let respelled_created = [&v1_payload[..created_at], &[0x80; 9][..], &[0x02, 0, 0][..]].concat();
    let refused = [
        (signed(2, &respelled_created), 6),
        (v3, 3),
        (v0, 3),
        (v1_header, 5),
        (signed(1, full_payload), 6),
        (signed(2, v1_payload), 6),
        (signed(2, &[v1_payload, &[2, 0]].concat()), 6),
        (signed(2, &[v1_payload, &[0, 2]].concat()), 6),
        (signed(2, &[v1_payload, &[0, 0, 0]].concat()), 6),
        (signed(2, &with_gyro[..with_gyro.len() - 1]), 6),
        (
            signed(2, &respelled_unit(&[0x80, 0x80, 0x80, 0x80, 0x80, 0x00])),
            6,
        ),
        (
            signed(2, &respelled_unit(&[0x80, 0x80, 0x80, 0x80, 0x10])),
            6,
        ),
        (signed(2, &nan_gyro), 7),
    ];
    let blobs: Vec<Vec<u8>> = refused.iter().map(|(b, _)| b.clone()).collect();
    let got = c_decode(dir.path(), &blobs);
    for ((blob, rc), got) in refused.iter().zip(&got) {
        assert!(shared::blob::decode(blob).is_err(), "Rust accepts {rc}");
        assert_eq!(*got, format!("rc {rc}"));
    }

    // Every truncation and every single-bit flip of the full version 2 blob is refused.
    let out = run(dir.path(), &format!("sweep {}\n", hex(full)));
    assert_eq!(out.trim(), format!("sweep {} 0", full.len()));
}

#[test]
fn c_header_with_gyro_and_temperature_model_initialises_what_it_decodes() {
    let unit = paper_input_unit();
    let mut cal = firmware::paper_unit::calibration();
    cal.gyro = Some(firmware::paper_unit::typical_gyro());
    cal.temperature = Some(firmware::paper_unit::typical_thermal_model());
    let input = ExportInput::for_tests(&unit, cal);
    let text = render_header(&input).unwrap();
    assert!(text.contains("Gyro correction: present"), "{text}");
    assert!(text.contains("Temperature model: present"), "{text}");
    let dir = tempfile::tempdir().unwrap();
    write_package(dir.path(), &input);
    std::fs::write(dir.path().join("main.c"), format!("{PRINT_CAL_C}{MAIN_C}")).unwrap();
    compile(dir.path(), &["main.c", "acal_blob.c", "acal_device.c"]);
    let out = run(dir.path(), "");
    let line = |tag: &str| {
        out.lines()
            .find(|l| l.split(' ').next() == Some(tag))
            .unwrap_or_else(|| panic!("no '{tag}' in {out}"))
            .to_string()
    };
    assert_eq!(line("decode"), "decode 0");
    let want = expected_fields(
        &cal,
        UnitId::parse_hex("a1b2c3d4e5f60718293a4b5c").unwrap(),
        0,
    );
    assert!(want.starts_with("0 0 1 1 1 0 "), "{want}");
    for tag in ["decoded", "initialiser"] {
        assert_eq!(normalised(&line(tag)), want, "{tag}");
    }
}

#[test]
fn c_header_needs_a_unit_id() {
    let unit = UnitFile::paper_unit();
    let input = ExportInput::for_tests(&unit, unit.to_calibration().unwrap());
    let e = render_header(&input).unwrap_err();
    assert!(e.to_string().contains("unit_id"), "{e}");
}

/// Drives the written package: `c u w wd` (ACAL_COMPENSATOR, static and full), `o w` (an estimator at
/// 1000 Hz, corner 20 Hz), `g t u w wd` (a copy refreshed at t, gyro corrected, compensated), `r`
/// (restart) and `s has_t t u w` (the device: temperature, then the sample); values as float bits.
const PACKAGE_MAIN_C: &str = r#"
#include <stdio.h>
#include <string.h>
#include "acal_calibration.h"
static void read_floats(float *v, int n) {
    for (int i = 0; i < n; i++) {
        unsigned b = 0;
        if (scanf("%x", &b) != 1) b = 0;
        memcpy(&v[i], &b, sizeof b);
    }
}
static void print_floats(const float *v, int n) {
    for (int i = 0; i < n; i++) {
        unsigned b;
        memcpy(&b, &v[i], sizeof b);
        printf(" %08x", b);
    }
}
int main(void) {
    char tag[8];
    struct acal_device dev;
    struct acal_omega_dot est;
    const struct acal_thermal *th = ACAL_THERMAL_OR_NULL;
    if (acal_device_init(&dev, &ACAL_COMPENSATOR, th, 1000.0f) != 0) return 1;
    if (acal_omega_dot_init(&est, 1000.0f, 20.0f) != 0) return 1;
    while (scanf("%7s", tag) == 1) {
        float v[10], a[3], b[3];
        if (strcmp(tag, "c") == 0) {
            read_floats(v, 9);
            acal_compensate_static(&ACAL_COMPENSATOR, v, a);
            acal_compensate(&ACAL_COMPENSATOR, v, v + 3, v + 6, b);
            printf("c");
            print_floats(a, 3);
            print_floats(b, 3);
        } else if (strcmp(tag, "o") == 0) {
            read_floats(v, 3);
            acal_omega_dot_update(&est, v, a);
            printf("o");
            print_floats(a, 3);
        } else if (strcmp(tag, "g") == 0 && th != NULL) {
            struct acal_compensator c = ACAL_COMPENSATOR;
            read_floats(v, 10);
            printf("g %d", (int)acal_refresh(&c, th, v[0]));
            acal_correct_rate(&c, v + 4, a);
            acal_compensate(&c, v + 1, a, v + 7, b);
            print_floats(a, 3);
            print_floats(b, 3);
        } else if (strcmp(tag, "r") == 0) {
            acal_device_restart(&dev);
            continue;
        } else if (strcmp(tag, "s") == 0) {
            read_floats(v, 8);
            if (v[0] != 0.0f) acal_device_temperature(&dev, v[1]);
            printf("s %d", acal_device_sample(&dev, v + 2, v + 5, a, b));
            print_floats(a, 3);
        } else {
            return 2;
        }
        printf("\n");
    }
    return 0;
}
"#;

/// Compiles the package in `dir` with `flags` into `dir/prog`.
fn compile_package(dir: &Path, flags: &[&str]) {
    let out = Command::new("cc")
        .current_dir(dir)
        .args(flags)
        .args([
            "main.c",
            "acal_blob.c",
            "acal_device.c",
            "-lm",
            "-o",
            "prog",
        ])
        .output()
        .expect("a C compiler runs");
    assert!(
        out.status.success(),
        "cc {flags:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
}

/// Exports `cal`'s C package with [`write_package`] into `dir/pkg` (refused over it without
/// `force`, then forced), with [`PACKAGE_MAIN_C`] beside it as `main.c`; checks that the package is
/// the six files and includes nothing else, and that the one-file format is the package's own
/// header. Returns `dir/pkg`.
fn exported_package(dir: &Path, cal: &Calibration) -> std::path::PathBuf {
    use crate::export::{render, ExportFormat, ExportInput, ExportOptions};
    let unit_id = UnitId::parse_hex("a1b2c3d4e5f60718293a4b5c").unwrap();
    let unit = UnitFile::from_calibration(cal, Some(unit_id), None);
    let input = ExportInput {
        unit: &unit,
        cal: *cal,
        noise: None,
        rostopic: "/imu0",
        driver_scale_m_s2_per_out: None,
        options: ExportOptions::default(),
    };
    let out = dir.join("pkg");
    super::write_package(&out, &input, false).unwrap();
    // Never over an existing package without force.
    assert!(super::write_package(&out, &input, false).is_err());
    super::write_package(&out, &input, true).unwrap();
    let mut written: Vec<String> = std::fs::read_dir(&out)
        .unwrap()
        .map(|e| e.unwrap().file_name().into_string().unwrap())
        .collect();
    written.sort();
    assert_eq!(
        written,
        [
            "acal_blob.c",
            "acal_blob.h",
            "acal_calibration.h",
            "acal_device.c",
            "acal_device.h",
            "example.c"
        ]
    );
    // The header includes nothing the package does not hold.
    let header = std::fs::read_to_string(out.join("acal_calibration.h")).unwrap();
    for inc in header.lines().filter_map(|l| l.strip_prefix("#include \"")) {
        assert!(written.iter().any(|w| inc.starts_with(w.as_str())), "{inc}");
    }
    // The one-file format is the package's own header.
    assert_eq!(render(&input, ExportFormat::CHeader).unwrap(), header);
    std::fs::write(out.join("main.c"), PACKAGE_MAIN_C).unwrap();
    out
}

/// The input lines for [`PACKAGE_MAIN_C`] and the lines it must print, from the Rust `f32` path:
/// the firmware's shared vectors named by `vectors` (`"comp"`: compensation and ω̇ estimator,
/// `"gyro-temp"`: temperature refresh and gyro correction), then a recording's rows through host
/// apply's path. One definition, so that every compiler and target checks the same vectors.
fn package_vectors(cal: &Calibration, vectors: &str) -> (String, Vec<String>) {
    use crate::apply::Applier;
    use firmware::testvectors::OMEGA_DOT_SEQ;
    use shared::LeverMode;
    let mut stdin = String::new();
    let mut want: Vec<String> = Vec::new();
    let bits = |v: &[u32]| v.iter().map(|b| format!(" {b:08x}")).collect::<String>();
    if vectors == "comp" {
        for c in COMP_CASES {
            stdin += &format!("c {}", hex_line(c.u.iter().chain(&c.w).chain(&c.wd)));
            want.push(format!("c{}{}", bits(&c.out_static), bits(&c.out_full)));
        }
        for (w, wd) in OMEGA_DOT_SEQ {
            stdin += &format!("o {}", hex_line(w));
            want.push(format!("o{}", bits(wd)));
        }
    } else {
        for c in GYRO_TEMP_CASES {
            let temp = f32::from_bits(c.temp_c);
            let state = if (-20.0..=60.0).contains(&temp) { 0 } else { 1 };
            stdin += &format!(
                "g {}",
                hex_line(
                    std::iter::once(&c.temp_c)
                        .chain(&c.u)
                        .chain(&c.w)
                        .chain(&c.wd)
                )
            );
            want.push(format!("g {state}{}{}", bits(&c.rate), bits(&c.out_full)));
        }
    }
    // A recording's rows through host apply's path: spins, a rate ramp (ω̇ ≠ 0), a temperature
    // sweep past the valid range, a non-finite row, segment changes.
    let model = ForwardModel::new(cal).unwrap();
    let gyro = cal.gyro.unwrap_or(GyroCorrection::PERFECT);
    let mut applier = Applier::new(cal, LeverMode::RateAndAcceleration, 1000.0).unwrap();
    for k in 0..900usize {
        let segment = k / 300;
        if k > 0 && k % 300 == 0 {
            stdin += "r\n";
        }
        let t = k as f64 * 1e-3;
        let omega = [
            3.0 * (7.0 * t).sin(),
            -2.0 + 4.0 * t,
            1.5 * (segment as f64),
        ];
        let omega_dot = [21.0 * (7.0 * t).cos(), 4.0, 0.0];
        let f = [9.0 * (0.3 * t).cos(), 2.0, -4.0 + t];
        let mut u = model
            .outputs(&BodyMotion {
                f_o: BodySpecificForce { m_s2: f },
                omega: BodyRate { rad_s: omega },
                omega_dot: BodyAngularAccel { rad_s2: omega_dot },
            })
            .raw;
        if k == 450 {
            u[1] = f64::NAN;
        }
        let w: [f64; 3] = std::array::from_fn(|i| {
            crate::export::linalg::dot(&gyro.matrix[i], &omega) + gyro.bias_rad_s[i]
        });
        let temp_c = (k % 3 != 2).then_some(-30.0 + 0.11 * k as f64);
        let row = recording::session::reader::Row {
            segment: "s",
            segment_index: segment,
            t_s: t,
            u,
            w_rad_s: w,
            temp_c,
        };
        let f_ref = applier.row(&row);
        let head = [
            u32::from(temp_c.is_some()) * 1.0f32.to_bits(),
            (temp_c.unwrap_or(0.0) as f32).to_bits(),
        ];
        let uw: Vec<u32> = u.iter().chain(&w).map(|v| (*v as f32).to_bits()).collect();
        stdin += &format!("s {}", hex_line(head.iter().chain(&uw)));
        want.push(match f_ref {
            Some(f) => format!("s 0{}", bits(&f.map(f32::to_bits))),
            None => "s -1 00000000 00000000 00000000".into(),
        });
    }
    (stdin, want)
}

/// Checks what [`PACKAGE_MAIN_C`] printed against [`package_vectors`]' lines, bit for bit; `what`
/// names the run in the failure message.
fn assert_package_output(got: &str, want: &[String], what: &str) {
    let got: Vec<&str> = got.lines().collect();
    assert_eq!(got.len(), want.len(), "{what}: line count");
    for (g, w) in got.iter().zip(want) {
        // A refused sample leaves the outputs as they were (the program's zeros).
        let g = if g.starts_with("s -1") {
            "s -1 00000000 00000000 00000000"
        } else {
            g
        };
        assert_eq!(g, w, "{what}");
    }
}

/// The package `host export --format c --out DIR` writes (through the command's own `run`),
/// compiled at -O0 and strictly at -O2, run on the firmware's shared vectors and on a recording's
/// rows: bit for bit the Rust device's and host apply's f32 path.
#[test]
fn c_package_written_by_the_command_is_self_contained_and_bit_exact() {
    for (cal, vectors) in [
        (firmware::paper_unit::calibration(), "comp"),
        (imperfect_unit(), "gyro-temp"),
    ] {
        let dir = tempfile::tempdir().unwrap();
        let out = exported_package(dir.path(), &cal);
        let (stdin, want) = package_vectors(&cal, vectors);
        for flags in [
            &["-O0"][..],
            &["-O2", "-Wall", "-Wextra", "-Werror", "-std=c99"][..],
        ] {
            compile_package(&out, flags);
            let got = run(&out, &stdin);
            assert_package_output(&got, &want, &format!("{vectors} {flags:?}"));
        }
    }
}

/// Runs `dir/prog` with `args`; its standard output.
fn run_with_args(dir: &Path, args: &[String]) -> String {
    let out = Command::new(dir.join("prog")).args(args).output().unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8(out.stdout).unwrap()
}

/// The values of the line of `out` that starts with `tag`, as `f32` bits (`%.9g` round-trips a
/// `float`).
fn printed_bits(out: &str, tag: &str) -> Vec<u32> {
    let line = out
        .lines()
        .find_map(|l| l.strip_prefix(&format!("{tag} ")))
        .unwrap_or_else(|| panic!("no '{tag}' in {out}"));
    line.split(' ')
        .map(|v| v.parse::<f32>().unwrap().to_bits())
        .collect()
}

/// `example.c` of the package the command writes, built as its comment says (with the strict flags
/// too) and run without arguments (the unit at rest, z up, the gyro reading its bias) and with a
/// sample and a temperature: what it prints is host apply's specific force and rate for the same
/// sample, bit for bit, and the decoded blob's unit and sections.
#[test]
fn c_package_example_decodes_corrects_one_sample_and_prints_host_applys_result() {
    use crate::apply::Applier;
    // The sample given on the command line: u, w (rad/s), temperature (°C).
    type Given = ([f32; 3], [f32; 3], f32);
    let cases: [(Calibration, Option<Given>); 3] = [
        (firmware::paper_unit::calibration(), None),
        (imperfect_unit(), None),
        (
            imperfect_unit(),
            Some(([0.31, -0.52, 2.71], [0.4, -1.25, 2.0], 41.5)),
        ),
    ];
    for (cal, given) in cases {
        let dir = tempfile::tempdir().unwrap();
        let pkg = exported_package(dir.path(), &cal);
        compile(&pkg, &["example.c", "acal_blob.c", "acal_device.c"]);
        let s = &cal.statics;
        let gyro = cal.gyro.unwrap_or(GyroCorrection::PERFECT);
        let at_rest = (
            std::array::from_fn(|i| {
                (s.zero_bias_out[i] + if i == 2 { s.scale_out_per_g[2] } else { 0.0 }) as f32
            }),
            gyro.bias_rad_s.map(|b| b as f32),
        );
        let (u, w) = given.map_or(at_rest, |(u, w, _)| (u, w));
        let temp_c = given.map(|(_, _, t)| t);
        let mut args: Vec<String> = Vec::new();
        if let Some(t) = temp_c {
            args = u
                .iter()
                .chain(&w)
                .chain([&t])
                .map(|v| format!("{v:e}"))
                .collect();
        }
        let out = run_with_args(&pkg, &args);
        let mut applier =
            Applier::new(&cal, shared::LeverMode::RateAndAcceleration, 1000.0).unwrap();
        let f = applier
            .row(&recording::session::reader::Row {
                segment: "s",
                segment_index: 0,
                t_s: 0.0,
                u: u.map(f64::from),
                w_rad_s: w.map(f64::from),
                temp_c: temp_c.map(f64::from),
            })
            .unwrap();
        assert_eq!(printed_bits(&out, "u"), u.map(f32::to_bits), "{out}");
        assert_eq!(printed_bits(&out, "f_m_s2"), f.map(f32::to_bits), "{out}");
        let rate = applier.rate_rad_s().map(f32::to_bits);
        assert_eq!(printed_bits(&out, "omega_rad_s"), rate, "{out}");
        let sections = match cal.gyro {
            Some(_) => "gyro present, temperature model present",
            None => "gyro absent, temperature model absent",
        };
        let first = out.lines().next().unwrap();
        assert!(
            first.starts_with("unit a1b2c3d4e5f60718293a4b5c, gravity "),
            "{first}"
        );
        assert!(first.ends_with(sections), "{first}");
        // At rest with z up the unit reads about 1 g on z (its misalignments tilt it by ~1°).
        if given.is_none() {
            let f_g = f.map(|v| f64::from(v) / cal.gravity_m_s2);
            assert!(
                (f_g[2] - 1.0).abs() < 1e-3 && f_g[0].abs() < 0.05,
                "{f_g:?}"
            );
        }
    }
}

#[path = "cross_tests.rs"]
mod cross_tests;

#[path = "fusion_tests.rs"]
mod fusion_tests;

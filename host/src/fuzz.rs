//! Fuzz targets: every parser of outside input, called on arbitrary bytes (`samples.csv`, `plan.toml`,
//! unit files, blobs, wire frames, a logger's CSV, the bare `samples.csv` of `host noise`, and the
//! binary logs: PX4 ULog, ArduPilot DataFlash, MCAP). Each target must return
//! (an `Ok` or a typed error) without panicking and within bounded memory; the properties a parsed
//! value must have are checked with `assert!`, so a violation is a crash the fuzzer reports.
//!
//! Two drivers call the same [`Target::fuzz_one`]:
//! - coverage-guided, libFuzzer through cargo-fuzz (`fuzz/`, nightly only):
//!   `cargo +nightly fuzz run samples_csv -- -runs=1000000`;
//! - the stable driver [`drive`]: seeded mutations of a small corpus of valid inputs plus random
//!   bytes, from the simulator's RNG, so a run is reproducible from its seed:
//!   `cargo run --release -p host --features fuzz --example fuzz -- all 1000000` (a short run is a unit test).

pub(crate) mod logs;

use estimator::unit_file::UnitFile;
use recording::session::import::{read_logger, GyroUnit, ImportOptions, TimeSource, MAX_ROWS};
use recording::session::{read_samples, Plan};
use shared::rng::Rng;
use std::path::Path;

/// The parsers under test.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Target {
    /// `samples.csv` against a fixed plan (the streaming reader).
    SamplesCsv,
    /// `plan.toml`.
    PlanToml,
    /// A unit file or `calibration.toml`.
    UnitFile,
    /// A calibration blob (`calibration.bin`, or what a device returns).
    Blob,
    /// Wire frames: the device's frame receiver and request handler, and the host's decoder.
    Wire,
    /// A logger's CSV (`host segment`'s importer), with a time column and with a sample rate.
    LoggerCsv,
    /// A bare `samples.csv` given to `host noise` (its two passes and the Allan analysis).
    NoiseCsv,
    /// A PX4 ULog (`host segment`'s binary readers, `session::logs`).
    Ulog,
    /// An ArduPilot DataFlash log.
    DataFlash,
    /// An MCAP file (a ROS 2 bag).
    Mcap,
}

impl Target {
    /// Every target.
    pub const ALL: [Target; 10] = [
        Target::SamplesCsv,
        Target::PlanToml,
        Target::UnitFile,
        Target::Blob,
        Target::Wire,
        Target::LoggerCsv,
        Target::NoiseCsv,
        Target::Ulog,
        Target::DataFlash,
        Target::Mcap,
    ];

    /// The name used on the command line and by `fuzz/fuzz_targets/`.
    pub fn name(self) -> &'static str {
        match self {
            Target::SamplesCsv => "samples_csv",
            Target::PlanToml => "plan_toml",
            Target::UnitFile => "unit_file",
            Target::Blob => "blob",
            Target::Wire => "wire",
            Target::LoggerCsv => "logger_csv",
            Target::NoiseCsv => "noise_csv",
            Target::Ulog => "ulog",
            Target::DataFlash => "dataflash",
            Target::Mcap => "mcap",
        }
    }

    /// The target called `name`.
    pub fn from_name(name: &str) -> Option<Target> {
        Target::ALL.into_iter().find(|t| t.name() == name)
    }

    /// Runs the parser on `data`.
    pub fn fuzz_one(self, data: &[u8]) {
        match self {
            Target::SamplesCsv => samples_csv(data),
            Target::PlanToml => plan_toml(data),
            Target::UnitFile => unit_file(data),
            Target::Blob => blob(data),
            Target::Wire => wire(data),
            Target::LoggerCsv => logger_csv(data),
            Target::NoiseCsv => noise_csv(data),
            Target::Ulog => logs::ulog(data),
            Target::DataFlash => logs::dataflash(data),
            Target::Mcap => logs::mcap(data),
        }
    }

    /// Valid inputs the mutations start from.
    pub fn corpus(self) -> Vec<Vec<u8>> {
        match self {
            Target::SamplesCsv => vec![
                SAMPLES.as_bytes().to_vec(),
                SAMPLES.replace('\n', "\r\n").into_bytes(),
            ],
            Target::PlanToml => vec![
                FUZZ_PLAN.as_bytes().to_vec(),
                recording::session::builtin::load_plan("short-oblique")
                    .map(|p| p.to_toml().into_bytes())
                    .unwrap_or_default(),
            ],
            Target::UnitFile => vec![estimator::unit_file::PAPER_UNIT_TOML.as_bytes().to_vec()],
            Target::Blob => {
                let b = paper_blob();
                let payload = b
                    .get(8..b.len().saturating_sub(4))
                    .unwrap_or_default()
                    .to_vec();
                vec![b, payload]
            }
            Target::Wire => wire_corpus(),
            Target::LoggerCsv => logger_corpus(),
            Target::NoiseCsv => vec![noise_corpus()],
            Target::Ulog => vec![logs::ulog_corpus()],
            Target::DataFlash => vec![logs::dataflash_corpus()],
            Target::Mcap => vec![
                logs::mcap_corpus(None),
                logs::mcap_corpus(Some(::mcap::Compression::Lz4)),
                logs::mcap_corpus(Some(::mcap::Compression::Zstd)),
            ],
        }
    }
}

const FUZZ_PLAN: &str = r#"
output_unit = "V"
sample_rate_hz = 100
[[segment]]
name = "x+"
up_b = [1, 0, 0]
duration_s = 1
[[segment]]
name = "z- 100"
up_b = [0, 0, -1]
rate_deg_s = 100
rate_end_deg_s = 150
"#;

const SAMPLES: &str = "segment,t_s,u_x,u_y,u_z,w_x,w_y,w_z\n\
x+,0,2.805,2.38,2.43,0.001,0,0\n\
x+,0.01,2.806,2.381,2.43,0,-0.002,0\n\
z- 100,0.02,2.4,2.38,2.03,0,0,-1.745\n\
z- 100,0.03,2.4,2.38,2.03,0,0,-1.746\n";

fn fuzz_plan() -> &'static Plan {
    static PLAN: std::sync::OnceLock<Plan> = std::sync::OnceLock::new();
    PLAN.get_or_init(|| Plan::parse(FUZZ_PLAN).expect("the fuzz plan is valid"))
}

/// `samples.csv`: the reader returns statistics or an error naming a line; statistics are of rows.
pub(crate) fn samples_csv(data: &[u8]) {
    if let Ok((stats, report)) = read_samples(data, fuzz_plan(), Path::new("samples.csv")) {
        let counted: u64 = stats.iter().map(|s| s.count + s.rejected_rows).sum();
        assert!(counted <= report.rows, "{counted} > {}", report.rows);
        assert!(report.bytes <= data.len() as u64);
    }
}

/// `plan.toml`: a plan that parses re-serialises to itself.
pub(crate) fn plan_toml(data: &[u8]) {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    if let Ok(plan) = Plan::parse(text) {
        let again = Plan::parse(&plan.to_toml()).expect("a valid plan re-reads");
        assert_eq!(again.segments.len(), plan.segments.len());
    }
}

/// A unit file: one that parses and describes a calibration round-trips through its TOML.
pub(crate) fn unit_file(data: &[u8]) {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let Ok(file) = UnitFile::parse(text) else {
        return;
    };
    if let Ok(cal) = file.to_calibration() {
        let text = UnitFile::from_calibration(&cal, None, file.uncertainty.clone()).to_toml();
        let back = UnitFile::parse(&text).expect("a written unit file re-reads");
        assert_eq!(back.to_calibration().ok(), Some(cal));
    }
}

/// A blob: one that decodes re-encodes to the same calibration and makes a compensator. The bytes are
/// tried as they are and as a payload behind a valid header and CRC, so that mutations reach the
/// payload's decoding and range checks rather than stopping at the CRC.
pub(crate) fn blob(data: &[u8]) {
    check_blob(data);
    if let Ok(n) = u16::try_from(data.len()) {
        let mut sealed = Vec::with_capacity(data.len() + 12);
        sealed.extend_from_slice(&shared::blob::BLOB_MAGIC);
        sealed.extend_from_slice(&shared::blob::BLOB_FORMAT_VERSION.to_le_bytes());
        sealed.extend_from_slice(&n.to_le_bytes());
        sealed.extend_from_slice(data);
        let crc = crc::Crc::<u32>::new(&crc::CRC_32_ISO_HDLC).checksum(&sealed);
        sealed.extend_from_slice(&crc.to_le_bytes());
        check_blob(&sealed);
    }
}

fn check_blob(bytes: &[u8]) {
    if let Ok(b) = shared::blob::decode(bytes) {
        let (again, n) = b.to_bytes().expect("a decoded blob re-encodes");
        assert_eq!(shared::blob::decode(&again[..n]), Ok(b));
        assert!(
            shared::Compensator::new(&b.calibration, shared::LeverMode::RateAndAcceleration)
                .is_ok(),
            "the device cannot use a blob its decoder accepts: {b:?}"
        );
    }
}

/// Wire frames: the device's receiver and request handler take any bytes (every request gets an
/// answer, never a panic), and the host decodes any frame to a message or a typed error.
pub(crate) fn wire(data: &[u8]) {
    use firmware::protocol::{FrameReceiver, Received};
    use firmware::{AbStore, Controller, DeviceInfo, RamNorFlash};
    use shared::wire::{decode_frame, Board, DeviceToHost, HostToDevice};
    const ERASE: usize = 4096;
    let mut mem = [0xFFu8; 2 * ERASE];
    let Ok(store) = AbStore::new(RamNorFlash::<ERASE>::new(&mut mem), 0, ERASE as u32) else {
        panic!("the RAM store opens");
    };
    let info = DeviceInfo {
        unit_id: shared::UnitId([7; 12]),
        board: Board::Simulated,
        sample_rate_hz: 1000,
        virtual_table: true,
        output_unit: shared::OutputUnit::Volts,
    };
    let mut device = Controller::boot(info, store, shared::LeverMode::RateAndAcceleration);
    let mut rx = FrameReceiver::new();
    for &b in data {
        match rx.push(b) {
            Some(Received::Message(m)) => {
                let _ = device.handle(m);
                // A write's store, as the board's idle loop runs it.
                if let Some(mut job) = device.take_store_job() {
                    job.run();
                    let _ = device.finish_store(job);
                }
            }
            Some(Received::Error(_)) | None => {}
        }
    }
    let mut frame = Vec::with_capacity(64);
    for chunk in data.split(|&b| b == 0) {
        frame.clear();
        frame.extend_from_slice(chunk);
        let _ = decode_frame::<DeviceToHost>(&mut frame);
        frame.clear();
        frame.extend_from_slice(chunk);
        let _ = decode_frame::<HostToDevice>(&mut frame);
    }
}

/// The importer's two ways to time rows: a column `t` in m/s² and °/s, and 100 Hz in g and rad/s.
fn logger_options() -> &'static [ImportOptions; 2] {
    static OPTIONS: std::sync::OnceLock<[ImportOptions; 2]> = std::sync::OnceLock::new();
    OPTIONS.get_or_init(|| {
        [
            ImportOptions::new(
                TimeSource::Column("t".into()),
                shared::OutputUnit::MetresPerSecondSquared,
                GyroUnit::DegPerS,
                crate::cli::spelling::FLAGS,
            ),
            ImportOptions::new(
                TimeSource::RateHz(100.0),
                shared::OutputUnit::StandardGravity,
                GyroUnit::RadPerS,
                crate::cli::spelling::FLAGS,
            ),
        ]
    })
}

/// A logger's CSV: a recording the importer accepts has as many times as rows, at least 100 and
/// at most `MAX_ROWS` of them, every step back or repeat of time among its jumps, only finite values
/// and a positive rate.
pub(crate) fn logger_csv(data: &[u8]) {
    for options in logger_options() {
        let Ok(rec) = read_logger(data, Path::new("raw.csv"), options) else {
            continue;
        };
        let n = rec.len();
        assert!((100..=MAX_ROWS).contains(&n), "{n} rows");
        assert!(rec.acc.len() == n && rec.gyro_rad_s.len() == n);
        // A repeat or a step back is kept, but never silently: each is one of the jumps that no
        // still interval spans and no turn is integrated across.
        let jumps = rec.jumps();
        assert!(
            rec.t_s
                .windows(2)
                .enumerate()
                .all(|(i, w)| w[1] > w[0] || jumps.iter().any(|j| j.row == i)),
            "a time step back not among the recording's jumps"
        );
        let values = rec.acc.iter().chain(&rec.gyro_rad_s).flatten();
        assert!(values.chain(&rec.t_s).all(|v| v.is_finite()));
        assert!(rec.rate_hz > 0.0, "rate {}", rec.rate_hz);
    }
}

/// A bare `samples.csv` for `host noise`: a report it gives is of `MIN_SAMPLES..=MAX_SAMPLES` rows
/// at a finite positive rate, six axes, one Allan point per cluster size of the curve (the octaves
/// and a ninth of the record).
pub(crate) fn noise_csv(data: &[u8]) {
    use outputs::noise::{allan::curve_sizes, MAX_SAMPLES, MIN_SAMPLES};
    if let Ok(r) = outputs::noise::analyse_csv_bytes(data, None, crate::cli::spelling::FLAGS) {
        let n = usize::try_from(r.samples).unwrap_or(usize::MAX);
        assert!((MIN_SAMPLES..=MAX_SAMPLES).contains(&n), "{n} rows");
        assert!(r.sample_rate_hz.is_finite() && r.sample_rate_hz > 0.0);
        assert_eq!(r.axes.len(), 6);
        let sizes = curve_sizes(n).len();
        assert!(r.axes.iter().all(|a| a.points.len() == sizes));
    }
}

/// 150 still rows at 100 Hz, as `t,acc_x,…` in m/s² and °/s, and with `;`, the columns in another
/// order, an index and an extra column, in g and rad/s.
fn logger_corpus() -> Vec<Vec<u8>> {
    let mut timed = String::from("t,acc_x,acc_y,acc_z,gyr_x,gyr_y,gyr_z\n");
    let mut indexed = String::from("n;gyr_z;ACC_X;acc_y;acc_z;gyr_x;gyr_y;temp\n");
    for k in 0..150 {
        let e = 1e-3 * ((k * 7 % 11) as f64 - 5.0);
        timed += &format!(
            "{:.2},{e},{},{},{},{e},-0.1\n",
            k as f64 * 0.01,
            -e,
            9.81 + e,
            0.5 + e
        );
        indexed += &format!("{k};{e};{e};0.001;{};0.002;{};25.0\n", 1.0 + e, -e);
    }
    vec![timed.into_bytes(), indexed.into_bytes()]
}

/// 100 rows of a still segment at 100 Hz between two short others.
fn noise_corpus() -> Vec<u8> {
    let mut text = String::from("segment,t_s,u_x,u_y,u_z,w_x,w_y,w_z\n");
    for k in 0..110 {
        let name = match k {
            0..5 => "x+",
            5..105 => "z+",
            _ => "y-",
        };
        let e = 1e-4 * ((k * 13 % 17) as f64 - 8.0);
        text += &format!(
            "{name},{:.2},{},{},{},{e},{},0.001\n",
            k as f64 * 0.01,
            2.4 + e,
            2.38 - e,
            2.83 + e,
            -e
        );
    }
    text.into_bytes()
}

fn paper_blob() -> Vec<u8> {
    let Ok(cal) = UnitFile::paper_unit().to_calibration() else {
        return Vec::new();
    };
    let blob = shared::blob::ParameterBlob {
        unit_id: shared::UnitId([7; 12]),
        calibration: cal,
        created_unix_s: 1_700_000_000,
    };
    blob.to_bytes()
        .map(|(b, n)| b[..n].to_vec())
        .unwrap_or_default()
}

fn wire_corpus() -> Vec<Vec<u8>> {
    use shared::wire::{encode_frame, HostToDevice, StreamKind, StreamRequest};
    let mut out = Vec::new();
    let mut buf = [0u8; 512];
    let blob = paper_blob();
    let mut msgs = vec![
        HostToDevice::Identify,
        HostToDevice::StopStream,
        HostToDevice::ReadCalibration { offset: 0 },
        HostToDevice::Stream(StreamRequest {
            kind: StreamKind::RawWindows,
            window_samples: 20,
        }),
    ];
    msgs.extend(shared::wire::blob_chunks(&blob).map(HostToDevice::WriteCalibration));
    let mut all = Vec::new();
    for m in &msgs {
        if let Ok(frame) = encode_frame(m, &mut buf) {
            out.push(frame.to_vec());
            all.extend_from_slice(frame);
        }
    }
    out.push(all);
    out
}

/// Counts of a [`drive`] run.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct DriveCounts {
    /// Inputs run.
    pub inputs: u64,
    /// Of which mutated corpus entries (the rest random bytes).
    pub mutated: u64,
}

/// Runs `n` inputs through `target`: mostly mutations (bit flips, byte sets, insertions, deletions,
/// duplicated slices, splices of two corpus entries, interesting bytes and numbers) of its corpus,
/// one in 16 purely random bytes. Deterministic in `seed`.
pub fn drive(target: Target, n: u64, seed: u64) -> DriveCounts {
    let corpus = target.corpus();
    let mut rng = Rng::new(seed, target as u64);
    let mut counts = DriveCounts::default();
    let mut input = Vec::with_capacity(4096);
    for _ in 0..n {
        input.clear();
        if corpus.is_empty() || rng.next_u64() % 16 == 0 {
            let len = (rng.next_u64() % 512) as usize;
            input.extend((0..len).map(|_| rng.next_u64() as u8));
        } else {
            let base = &corpus[(rng.next_u64() % corpus.len() as u64) as usize];
            input.extend_from_slice(base);
            let rounds = 1 + rng.next_u64() % 8;
            for _ in 0..rounds {
                mutate(&mut input, &corpus, &mut rng);
            }
            counts.mutated += 1;
        }
        target.fuzz_one(&input);
        counts.inputs += 1;
    }
    counts
}

/// Tokens that parsers treat specially.
const TOKENS: &[&[u8]] = &[
    b"nan",
    b"NaN",
    b"inf",
    b"-inf",
    b"1e308",
    b"1e-308",
    b"-0",
    b"1e9",
    b"0",
    b"\n",
    b"\r\n",
    b",",
    b"\"",
    b"[",
    b"]",
    b"=",
    b"[[segment]]",
    b"\xff",
    b"\xef\xbb\xbf",
    b"\x00",
    b"4294967295",
    b"18446744073709551616",
];

fn mutate(input: &mut Vec<u8>, corpus: &[Vec<u8>], rng: &mut Rng) {
    let len = input.len();
    let pos = |rng: &mut Rng, len: usize| {
        if len == 0 {
            0
        } else {
            (rng.next_u64() % len as u64) as usize
        }
    };
    match rng.next_u64() % 8 {
        0 if len > 0 => {
            let p = pos(rng, len);
            input[p] ^= 1 << (rng.next_u64() % 8);
        }
        1 if len > 0 => {
            let p = pos(rng, len);
            input[p] = rng.next_u64() as u8;
        }
        2 => {
            let p = pos(rng, len + 1).min(len);
            let t = TOKENS[(rng.next_u64() % TOKENS.len() as u64) as usize];
            input.splice(p..p, t.iter().copied());
        }
        3 if len > 0 => {
            let a = pos(rng, len);
            let b = (a + 1 + pos(rng, 64)).min(len);
            input.drain(a..b);
        }
        4 if len > 0 && len < 8192 => {
            let a = pos(rng, len);
            let b = (a + 1 + pos(rng, 256)).min(len);
            let piece = input[a..b].to_vec();
            let p = pos(rng, len);
            input.splice(p..p, piece);
        }
        5 if !corpus.is_empty() => {
            let other = &corpus[(rng.next_u64() % corpus.len() as u64) as usize];
            let cut = pos(rng, len + 1).min(len);
            let from = pos(rng, other.len() + 1).min(other.len());
            input.truncate(cut);
            input.extend_from_slice(&other[from..]);
        }
        6 if len > 0 => {
            // Replace a run of digits with another number.
            let p = pos(rng, len);
            let t = TOKENS[(rng.next_u64() % TOKENS.len() as u64) as usize];
            let end = (p + 1 + pos(rng, 8)).min(len);
            input.splice(p..end, t.iter().copied());
        }
        _ => {
            let p = pos(rng, len + 1).min(len);
            input.insert(p, rng.next_u64() as u8);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The short run of every target (the long one is `examples/fuzz.rs`).
    #[test]
    fn every_parser_survives_ten_thousand_mutated_inputs() {
        for t in Target::ALL {
            assert!(!t.corpus().iter().any(Vec::is_empty), "{t:?} corpus");
            for c in t.corpus() {
                t.fuzz_one(&c);
            }
            let counts = drive(t, 10_000, 1);
            assert_eq!(counts.inputs, 10_000);
            assert!(counts.mutated > 8_000, "{t:?}: {counts:?}");
        }
    }

    #[test]
    fn the_corpora_are_valid_inputs() {
        assert!(read_samples(SAMPLES.as_bytes(), fuzz_plan(), Path::new("s")).is_ok());
        assert!(Plan::parse(FUZZ_PLAN).is_ok());
        assert!(shared::blob::decode(&paper_blob()).is_ok());
        assert!(UnitFile::parse(estimator::unit_file::PAPER_UNIT_TOML).is_ok());
        // Each logger entry is read with one of the two options; the noise entry gives its still
        // segment's 100 rows at 100 Hz.
        for (entry, options) in logger_corpus().iter().zip(logger_options()) {
            let rec = read_logger(entry.as_slice(), Path::new("raw.csv"), options).unwrap();
            assert_eq!(rec.len(), 150);
            assert!((rec.rate_hz - 100.0).abs() < 1e-6, "{}", rec.rate_hz);
        }
        let r =
            outputs::noise::analyse_csv_bytes(&noise_corpus(), None, crate::cli::spelling::FLAGS)
                .unwrap();
        assert_eq!((r.segment.as_str(), r.samples), ("z+", 100));
        assert!(
            (r.sample_rate_hz - 100.0).abs() < 1e-9,
            "{}",
            r.sample_rate_hz
        );
    }
}

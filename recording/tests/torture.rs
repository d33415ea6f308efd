//! The readers under damage, property-based over all four formats: a simulated hand session written
//! as text, ULog, DataFlash and MCAP, one mutation at a seeded random place (a flipped bit in a
//! stamp, swapped or repeated messages, a repeated stamp, jitter, a gap, a cut file, a NaN value or
//! temperature, simulated time, reversed order, an oversized malformed format record), read back.
//! The property (docs/robustness.md, "Damaged time stamps"): every sample the mutation did not
//! damage is kept, at its own time and with its own values; at most 2 rows are lost per damaged
//! sample.
//!
//! `TORTURE_SEEDS=N cargo test -p recording --test torture -- --nocapture` runs N seeds per case
//! (default 3) and prints the cases run and the rows lost per damaged sample, per format and
//! mutation.

use recording::session::logs::{read_log_from, LogSource};
use recording::testkit::{
    csv_source, hand_session, write_csv, write_dataflash, write_mcap, write_mcap_with, write_ulog,
    LogSample,
};
use shared::rng::Rng;
use std::collections::{BTreeMap, HashMap};
use std::path::Path;

#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
enum Format {
    Text,
    Ulog,
    DataFlash,
    Mcap,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
enum Mutation {
    StampBitFlip,
    Swap,
    RepeatMessage,
    RepeatStamp,
    Jitter,
    Gap,
    Truncate,
    NanValue,
    NanTemperature,
    SimulatedTime,
    Reversed,
    MalformedFormat,
}

const MUTATIONS: [Mutation; 12] = [
    Mutation::StampBitFlip,
    Mutation::Swap,
    Mutation::RepeatMessage,
    Mutation::RepeatStamp,
    Mutation::Jitter,
    Mutation::Gap,
    Mutation::Truncate,
    Mutation::NanValue,
    Mutation::NanTemperature,
    Mutation::SimulatedTime,
    Mutation::Reversed,
    Mutation::MalformedFormat,
];

/// The clean session: the fixtures' hand session (6 000 rows, 60 s at 100 Hz), its clock started
/// 1000 s before, its temperature a ramp.
fn clean() -> Vec<LogSample> {
    let hand = hand_session();
    let t0 = hand[0].t_s;
    hand.iter()
        .enumerate()
        .map(|(k, s)| LogSample {
            t_s: 1000.0 + s.t_s - t0,
            temp_c: 30.0 + 1e-4 * k as f32,
            ..*s
        })
        .collect()
}

fn write(format: Format, samples: &[LogSample], recorder_offset_s: f64) -> Vec<u8> {
    match format {
        Format::Text => write_csv(samples),
        Format::Ulog => write_ulog(samples, None),
        Format::DataFlash => write_dataflash(samples),
        Format::Mcap => write_mcap(samples, None, recorder_offset_s),
    }
}

/// The samples with one mutation at a random place, the file, and how many samples were damaged
/// (a gap's samples and a cut file's tail count as removed, not damaged: `removed`).
struct Damaged {
    bytes: Vec<u8>,
    damaged: usize,
    removed: usize,
}

fn mutate(format: Format, m: Mutation, clean: &[LogSample], rng: &mut Rng) -> Damaged {
    let n = clean.len();
    let mut s = clean.to_vec();
    let at = rng.range(20.0, n as f64 - 20.0) as usize;
    let (mut damaged, mut removed, mut offset) = (1, 0, 0.0);
    match m {
        Mutation::StampBitFlip => {
            let bit = rng.range(14.0, 44.0) as u32;
            let us = (s[at].t_s * 1e6).round() as u64 ^ (1u64 << bit);
            s[at].t_s = us as f64 * 1e-6;
        }
        Mutation::Swap => {
            s.swap(at, at + 1);
            damaged = 2;
        }
        Mutation::RepeatMessage => s.insert(at, s[at]),
        Mutation::RepeatStamp => s[at].t_s = s[at - 1].t_s,
        Mutation::Jitter => {
            s.iter_mut().for_each(|x| x.t_s += rng.range(-1e-3, 1e-3));
            damaged = 0;
        }
        Mutation::Gap => {
            s.drain(at..at + 50);
            (damaged, removed) = (0, 50);
        }
        Mutation::NanValue => s[at].acc[rng.range(0.0, 3.0) as usize] = f32::NAN,
        Mutation::NanTemperature => {
            let upto = if rng.range(0.0, 1.0) < 0.5 { n } else { n / 5 };
            s[..upto].iter_mut().for_each(|x| x.temp_c = f32::NAN);
            damaged = 0;
        }
        Mutation::SimulatedTime => {
            let t0 = s[0].t_s;
            s.iter_mut().for_each(|x| x.t_s -= t0);
            offset = 1.7e9;
            damaged = 0;
        }
        Mutation::Reversed => {
            s.reverse();
            damaged = 0;
        }
        Mutation::Truncate => {}
        Mutation::MalformedFormat => {
            let bytes = match format {
                Format::Mcap => write_mcap_with(&s, None, 0.0, Some(at)),
                _ => malformed_format_record(write(format, &s, 0.0), format, n - at),
            };
            return Damaged {
                bytes,
                damaged: 1,
                removed: 0,
            };
        }
    }
    let mut bytes = write(format, &s, offset);
    if m == Mutation::Truncate {
        let cut = rng.range(0.5, 0.95);
        let mut keep = (bytes.len() as f64 * cut) as usize;
        // A cut exactly between two messages leaves a shorter whole log, which no reader can tell
        // from one the logger closed there: the mutation cuts through a message.
        if message_starts(format, &bytes).contains(&keep) {
            keep -= 1;
        }
        bytes.truncate(keep);
        // About the samples after the cut are removed; the one the cut runs through is damaged.
        removed = match format {
            // A text file's rows are its complete lines after the header.
            Format::Text => n + 1 - bytes.iter().filter(|&&b| b == b'\n').count(),
            _ => n - (n as f64 * cut) as usize,
        };
        damaged = 1;
    }
    Damaged {
        bytes,
        damaged,
        removed,
    }
}

/// Where each message (a binary log's record) of a file from [`write`] begins: ULog's after the
/// 16-byte header (`u16` size, `u8` type, the body), DataFlash's at each `A3 95` its writer puts
/// before a message, MCAP's records after the 8-byte magic (`u8` opcode, `u64` length, the body).
/// None for a text file, whose cut is a line's.
fn message_starts(format: Format, file: &[u8]) -> Vec<usize> {
    let walk = |mut at: usize, header: usize, len: &dyn Fn(&[u8]) -> usize| {
        let mut starts = Vec::new();
        while at + header <= file.len() {
            starts.push(at);
            at += header + len(&file[at..]);
        }
        starts
    };
    match format {
        Format::Text => Vec::new(),
        Format::Ulog => walk(16, 3, &|m| usize::from(u16::from_le_bytes([m[0], m[1]]))),
        Format::DataFlash => (0..file.len().saturating_sub(1))
            .filter(|&i| file[i] == 0xA3 && file[i + 1] == 0x95)
            .collect(),
        Format::Mcap => walk(8, 9, &|m| {
            u64::from_le_bytes(m[1..9].try_into().unwrap()) as usize
        }),
    }
}

/// `file` with an oversized, malformed format record inserted before its last `tail` samples: a
/// text line of 100 000 bytes that is no row; a ULog format definition (`F`) of 60 000 bytes that
/// does not parse; a DataFlash `FMT` whose format has a type letter none defines and whose length
/// is the largest a record can claim.
fn malformed_format_record(mut file: Vec<u8>, format: Format, tail: usize) -> Vec<u8> {
    // Bytes per sample as the writers write them.
    let (at, record) = match format {
        Format::Text => {
            let lines: Vec<usize> = file
                .iter()
                .enumerate()
                .filter(|(_, &b)| b == b'\n')
                .map(|(i, _)| i + 1)
                .collect();
            let mut line = vec![b'x'; 100_000];
            line.push(b'\n');
            (lines[lines.len() - 1 - tail], line)
        }
        Format::Ulog => {
            let body: Vec<u8> = b"junk:float[0] x;"
                .iter()
                .copied()
                .cycle()
                .take(60_000)
                .collect();
            let mut record = (body.len() as u16).to_le_bytes().to_vec();
            record.push(b'F');
            record.extend(body);
            (file.len() - tail * 98, record)
        }
        Format::DataFlash => {
            let mut record = vec![0xA3, 0x95, 0x80, 0xB0, 255];
            for (s, n) in [("JUNK", 4), ("Qf?!", 16), ("TimeUS,A,B,C", 64)] {
                let mut v = s.as_bytes().to_vec();
                v.resize(n, 0);
                record.extend(v);
            }
            (file.len() - tail * 54, record)
        }
        Format::Mcap => unreachable!("the mcap crate writes its records"),
    };
    file.splice(at..at, record);
    file
}

fn source(format: Format) -> LogSource {
    match format {
        Format::Text => csv_source(),
        _ => LogSource::default(),
    }
}

/// Rows of the clean session the damaged read kept at their own time (within the jitter) with their
/// own values, and the last of them (index); panics on a kept row at another time.
fn kept_clean_rows(
    clean: &[LogSample],
    rec: &recording::session::import::Recording,
    jitter_s: f64,
    case: &str,
) -> (usize, usize) {
    // As f32: the writers' values, which a text file holds to the digits that give them back.
    let key = |a: [f64; 3]| a.map(|x| (x as f32).to_bits());
    let by_acc: HashMap<[u32; 3], (f64, usize)> = clean
        .iter()
        .enumerate()
        .map(|(k, s)| (key(s.acc.map(f64::from)), (s.t_s, k)))
        .collect();
    let mut offsets: Vec<f64> = rec
        .acc
        .iter()
        .zip(&rec.t_s)
        .filter_map(|(a, t)| by_acc.get(&key(*a)).map(|t0| t - t0.0))
        .collect();
    offsets.sort_by(f64::total_cmp);
    let offset = offsets[offsets.len() / 2];
    let (mut kept, mut last) = (0, 0);
    for (a, t) in rec.acc.iter().zip(&rec.t_s) {
        let Some(&(t0, k)) = by_acc.get(&key(*a)) else {
            continue;
        };
        last = last.max(k);
        assert!(
            (t - offset - t0).abs() <= jitter_s + 5e-5,
            "{case}: a row at {t} s kept at {} s from its own time",
            t - offset - t0
        );
        kept += 1;
    }
    (kept, last)
}

#[test]
fn a_damaged_sample_costs_at_most_two_rows_in_every_format() {
    let seeds: u64 = std::env::var("TORTURE_SEEDS")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(3);
    let clean = clean();
    let n = clean.len();
    let mut worst: BTreeMap<(Format, Mutation), (usize, f64)> = BTreeMap::new();
    let mut cut_losses: BTreeMap<Format, usize> = BTreeMap::new();
    for format in [Format::Text, Format::Ulog, Format::DataFlash, Format::Mcap] {
        for m in MUTATIONS {
            for seed in 0..seeds {
                let mut rng = Rng::new(seed, 40 + m as u64);
                let d = mutate(format, m, &clean, &mut rng);
                let case = format!("{format:?} {m:?} seed {seed}");
                let log = read_log_from(&d.bytes[..], &d.bytes, Path::new("x"), &source(format))
                    .unwrap_or_else(|e| panic!("{case}: refused: {e}"));
                let jitter = if m == Mutation::Jitter { 1e-3 } else { 0.0 };
                let (kept, last) = kept_clean_rows(&clean, &log.recording, jitter, &case);
                let removed = if m == Mutation::Truncate {
                    // The rows after the cut; the reader must have read up to it, or, in a chunked
                    // MCAP, up to the chunk the cut runs through (the format's unit of integrity:
                    // the crate's writer makes 1 MiB chunks, 3 000 messages).
                    let slack = if format == Format::Mcap { 3_200 } else { 200 };
                    assert!(
                        n - last <= d.removed + slack,
                        "{case}: read up to row {last} of a file cut after {}",
                        n - d.removed
                    );
                    assert!(
                        format == Format::Text
                            || log
                                .warnings
                                .iter()
                                .any(|w| w.to_string().contains("cut short")),
                        "{case}: {:?}",
                        log.warnings
                    );
                    let cut = cut_losses.entry(format).or_default();
                    *cut = (*cut).max((n - d.removed).saturating_sub(last + 1));
                    n - 1 - last
                } else {
                    d.removed
                };
                let lost = n - removed - kept.min(n - removed);
                assert!(
                    lost <= 2 * d.damaged,
                    "{case}: {lost} rows lost for {} damaged sample(s); warnings {:?} {:?}",
                    d.damaged,
                    log.warnings,
                    log.recording.time_repairs
                );
                if m == Mutation::NanTemperature
                    && matches!(format, Format::Ulog | Format::DataFlash)
                {
                    // Partly NaN: the column kept whole; NaN throughout: no temperature, said.
                    match log.recording.temp_c.as_ref() {
                        Some(t) => assert_eq!(t.len(), log.recording.len(), "{case}"),
                        None => assert!(
                            log.warnings
                                .iter()
                                .any(|w| w.to_string().contains("NaN in every sample")),
                            "{case}: {:?}",
                            log.warnings
                        ),
                    }
                }
                let per = lost as f64 / d.damaged.max(1) as f64;
                let w = worst.entry((format, m)).or_insert((0, 0.0));
                w.0 += 1;
                w.1 = w.1.max(per);
            }
        }
    }
    println!("format     mutation         cases  rows lost per damaged sample (worst)");
    for ((f, m), (cases, per)) in &worst {
        println!(
            "{:<10} {:<16} {cases:>5}  {per}",
            format!("{f:?}"),
            format!("{m:?}")
        );
    }
    for (f, lost) in &cut_losses {
        println!("{f:?}: a cut file lost at most {lost} rows before the cut");
    }
    println!("{} cases run", worst.values().map(|w| w.0).sum::<usize>());
}

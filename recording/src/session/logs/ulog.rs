//! PX4 ULog: the IMU's samples from `sensor_accel` + `sensor_gyro` (the sensors' own outputs before
//! PX4's calibration is applied, with the sensor's temperature), else from `sensor_combined` (already
//! corrected by PX4's calibration, no temperature: marked [`Recording::corrected_by`], which `noise`
//! reads and `segment` and `apply` refuse).
//!
//! Written against PX4's "ULog File Format" (docs.px4.io, `dev_log/ulog_file_format`) and its C
//! header `ulog_messages.h`, with pyulog's `core.py` (v1.3.0) as the reference reader: a 16-byte
//! header (7 magic bytes, version, start time), then messages of `u16 size, u8 type, payload`,
//! little-endian. Why our own reader: the Rust ULog crates are small, young and read the whole file
//! into memory or panic on damaged input; this one streams once, keeps only the chosen instance's IMU
//! topics, and bounds everything (a message is at most 65 535 bytes by its size field). What the
//! format definitions say, each field's place in a message, is `layout`.

use super::resume::Marker;
use super::stream::{read_by, take_times_of};
use super::{
    list_instances, pair_streams, read_exact_or_end, ImuError, Keep, Stream, StreamSample, TooMany,
};
use crate::session::import::Recording;
use crate::session::note::Note;
use crate::spelling::Spelling;
use std::collections::{BTreeSet, HashMap};
use std::io::Read;
use std::sync::Arc;

mod layout;
mod params;
mod window;
use layout::{layout, parse_format, Field, Layout, Topic, MAX_NESTING};
pub use params::read_params;
pub(crate) use window::{read_window, At, Resume};

/// The file's first seven bytes ("ULog" 01 12 35).
pub const MAGIC: [u8; 7] = [0x55, 0x4c, 0x6f, 0x67, 0x01, 0x12, 0x35];
/// Most format definitions kept: PX4 logs a few hundred topics.
const MAX_FORMATS: usize = 4096;
/// Most fields kept over all format definitions: PX4's few hundred topics have a few thousand.
/// A field costs about 100 bytes parsed (its type and name), so that a log of oversized
/// definitions (each up to 65 535 bytes, some 16 000 fields) costs no more than about 6 MB
/// however many it has; the definitions beyond it are left out (an IMU topic's own is kept).
pub(crate) const MAX_FIELDS: usize = 1 << 16;
/// Most bytes of field types and names kept over all format definitions (PX4's: some 60 KB), so
/// that a few fields of very long names cost no more.
pub(crate) const MAX_FIELD_BYTES: usize = 4 << 20;
/// `accelerometer_timestamp_relative` when the accelerometer sample is missing (PX4's
/// `sensor_combined_s::RELATIVE_TIMESTAMP_INVALID`).
const RELATIVE_TIMESTAMP_INVALID: i32 = 0x7fff_ffff;

/// Why a ULog cannot be read; each names the byte offset where it went wrong.
#[derive(Debug, thiserror::Error)]
pub enum UlogError {
    /// Reading failed.
    #[error("read error at byte {offset}")]
    Io {
        /// Where.
        offset: u64,
        /// The cause.
        source: std::io::Error,
    },
    /// Shorter than the 16-byte header.
    #[error("the file ends inside the 16-byte ULog header: it is cut short; copy it from the vehicle again")]
    ShortHeader,
    /// A format definition that does not parse.
    #[error(
        "byte {offset}: the format definition '{text}' is not 'name:type field;…': the log is \
         damaged; pyulog's ulog_info shows how far it reads"
    )]
    BadFormat {
        /// Where.
        offset: u64,
        /// The definition (cut to 80 characters).
        text: String,
    },
    /// A field of an IMU topic has a type no format defines, or nests too deep.
    #[error(
        "byte {offset}: topic '{topic}' has a field of type '{ty}' that no format defines (or \
         nested more than {MAX_NESTING} deep): the log is damaged or of an unknown kind"
    )]
    UnknownType {
        /// Where.
        offset: u64,
        /// The topic.
        topic: String,
        /// The type.
        ty: String,
    },
    /// An IMU topic lacks a field this reader needs.
    #[error(
        "byte {offset}: topic '{topic}' has no field '{field}' (its format: {format}); this PX4 \
         version logs it differently: convert the log to CSV with pyulog's ulog2csv and read that"
    )]
    MissingField {
        /// Where.
        offset: u64,
        /// The topic.
        topic: String,
        /// The field.
        field: &'static str,
        /// The topic's fields.
        format: String,
    },
    /// A data message shorter than its topic's fields.
    #[error(
        "byte {offset}: a '{topic}' message has {len} bytes, its format needs {need}: the log is damaged"
    )]
    ShortData {
        /// Where.
        offset: u64,
        /// The topic.
        topic: String,
        /// Its length.
        len: usize,
        /// The bytes the fields read need.
        need: usize,
    },
    /// Incompatible flags this reader does not know.
    #[error(
        "the log sets incompatible flags {flags:#x} this reader does not know (a newer ULog \
         version): convert it with a current pyulog (ulog2csv) and read the CSV"
    )]
    IncompatibleFlags {
        /// `incompat_flags` as one number (bit 0, appended data, is known).
        flags: u64,
    },
    /// Too many format definitions.
    #[error("more than {MAX_FORMATS} format definitions: not a PX4 log, or a damaged one")]
    TooManyFormats,
    /// No IMU for the instance, or too many samples.
    #[error(transparent)]
    Imu(#[from] ImuError),
    /// A rate given for a log whose accelerometer and gyro are separate topics at different
    /// rates: one rate cannot re-time both.
    #[error(
        "the rate option re-times every sample at one rate, but this log's sensor_accel and \
         sensor_gyro are separate topics of {accel} and {gyro} samples (different rates); its \
         stamps are the autopilot's sample times: leave the rate out"
    )]
    RateForSeparateTopics {
        /// Accelerometer samples.
        accel: usize,
        /// Gyro samples.
        gyro: usize,
    },
}

/// The reader's state while it streams the file.
#[derive(Default)]
struct State {
    /// The formats by name, shared with the survey's marks until a definition changes them.
    formats: Arc<HashMap<String, Vec<Field>>>,
    /// msg_id → the layout of an IMU topic of the chosen instance.
    subscribed: Arc<HashMap<u16, Layout>>,
    /// Every IMU topic and instance seen, for the error when the chosen one is absent.
    seen: BTreeSet<(Topic, u8)>,
    combined_acc: Stream,
    combined_gyro: Stream,
    accel: Stream,
    gyro: Stream,
    last_t_s: f64,
    dropouts: Vec<(u64, f64, u16)>,
    /// Where data was appended after the log was first closed (the flag bits message), ascending.
    appended: Vec<u64>,
    /// Format definitions that do not parse and define no IMU topic: how many, the first's byte.
    bad_formats: (u64, u64),
    /// The fields of `formats` and the bytes of their types and names, all told (at most
    /// [`MAX_FIELDS`] and [`MAX_FIELD_BYTES`]).
    fields: (usize, usize),
    /// Format definitions beyond [`MAX_FIELDS`] or [`MAX_FIELD_BYTES`] that define no IMU topic:
    /// how many, the first's byte.
    over_formats: (u64, u64),
}

impl UlogError {
    /// The error with the options named as `spelling` does (the reader says flags).
    pub fn spelled(self, spelling: Spelling) -> UlogError {
        match self {
            UlogError::Imu(e) => UlogError::Imu(e.spelled(spelling)),
            e => e,
        }
    }
}

/// Reads the IMU samples of `instance` (the topics' `multi_id`) from a ULog.
pub fn read<R: Read>(r: R, instance: u8) -> Result<(Recording, Vec<Note>), UlogError> {
    read_keeping(r, instance, &Keep::default(), None)
}

/// [`read`], each stream keeping what `keep` says.
pub(crate) fn read_keeping<R: Read>(
    mut r: R,
    instance: u8,
    keep: &Keep,
    rate_hz: Option<f64>,
) -> Result<(Recording, Vec<Note>), UlogError> {
    let mut header = [0u8; 16];
    match read_exact_or_end(&mut r, &mut header) {
        Ok(true) => {}
        Ok(false) => return Err(UlogError::ShortHeader),
        Err(e) if e.kind() == std::io::ErrorKind::UnexpectedEof => {
            return Err(UlogError::ShortHeader)
        }
        Err(source) => return Err(UlogError::Io { offset: 0, source }),
    }
    let mut st = State::new(keep, rate_hz);
    let mut offset = 16u64;
    let mut warnings = Vec::new();
    let mut marker = Marker::for_keep(keep);
    st.messages(
        &mut r,
        &mut offset,
        instance,
        None,
        marker.as_mut(),
        &mut warnings,
    )?;
    if let (count @ 1.., first) = st.bad_formats {
        warnings.push(Note::UlogBadFormats { count, first });
    }
    if let (count @ 1.., first) = st.over_formats {
        warnings.push(Note::UlogOverFormats { count, first });
    }
    if let (Some(marker), Keep::Survey(report)) = (marker, keep) {
        let resume = Resume {
            marks: marker.finish(st.take_times()),
            streams: st.streams().map(|s| s.at()),
            seen: st.seen.clone(),
            dropouts: st.dropouts.clone(),
            warnings: warnings.clone(),
        };
        if let Ok(mut r) = report.lock() {
            r.resume = Some(Arc::new(super::resume::Resume::Ulog(resume)));
        }
    }
    st.finish(instance, warnings)
}

/// Reads and drops the bytes from `offset` to `to`; `false` when the file ends first (said).
fn skip_to<R: Read>(
    r: &mut R,
    offset: &mut u64,
    to: u64,
    warnings: &mut Vec<Note>,
) -> Result<bool, UlogError> {
    let want = to - *offset;
    let got =
        std::io::copy(&mut r.take(want), &mut std::io::sink()).map_err(|source| UlogError::Io {
            offset: *offset,
            source,
        })?;
    *offset += got;
    if got < want {
        warnings.push(Note::UlogEndsBeforeAppended {
            offset: *offset,
            appended: to,
        });
    }
    Ok(got == want)
}

/// The fields of a format definition and the bytes of their types and names.
fn size(fields: &[Field]) -> (usize, usize) {
    let bytes = fields.iter().map(|f| f.ty.len() + f.name.len()).sum();
    (fields.len(), bytes)
}

fn cut_short(offset: u64) -> Note {
    Note::LastMessageCutShort { offset }
}

impl State {
    /// Empty streams that keep what `keep` says, re-timed at `rate_hz` (none: as stamped).
    fn new(keep: &Keep, rate_hz: Option<f64>) -> State {
        let mut st = State {
            combined_acc: Stream::new(keep),
            combined_gyro: Stream::new(keep),
            accel: Stream::new(keep),
            gyro: Stream::new(keep),
            ..State::default()
        };
        for s in [
            &mut st.combined_acc,
            &mut st.combined_gyro,
            &mut st.accel,
            &mut st.gyro,
        ] {
            s.retime(rate_hz);
        }
        st
    }

    fn streams(&self) -> [&Stream; 4] {
        [
            &self.combined_acc,
            &self.combined_gyro,
            &self.accel,
            &self.gyro,
        ]
    }

    fn streams_mut(&mut self) -> [&mut Stream; 4] {
        [
            &mut self.combined_acc,
            &mut self.combined_gyro,
            &mut self.accel,
            &mut self.gyro,
        ]
    }

    /// The samples read, all streams told.
    fn read(&self) -> usize {
        read_by(&self.streams())
    }

    /// A survey: the least and greatest time of the samples read since the last call.
    fn take_times(&mut self) -> (f64, f64) {
        take_times_of(self.streams_mut())
    }

    /// Reads the messages of `r` (at the file's byte `offset`) up to the byte `end` (`None`: the
    /// end of the file), setting `marker`'s marks on the way.
    fn messages<R: Read>(
        &mut self,
        r: &mut R,
        offset: &mut u64,
        instance: u8,
        end: Option<u64>,
        mut marker: Option<&mut Marker<At>>,
        warnings: &mut Vec<Note>,
    ) -> Result<(), UlogError> {
        let mut payload = vec![0u8; u16::MAX as usize];
        loop {
            if end.is_some_and(|e| *offset >= e) {
                break;
            }
            if let Some(m) = marker.as_deref_mut().filter(|m| m.due(self.read())) {
                let at = At {
                    formats: Arc::clone(&self.formats),
                    subscribed: Arc::clone(&self.subscribed),
                    appended: self.appended.clone(),
                    fields: self.fields,
                    streams: self.streams().map(|s| s.at()),
                };
                let times = self.take_times();
                m.set(*offset, at, times, self.read());
            }
            if !self.message_at(r, offset, &mut payload, instance, warnings)? {
                break;
            }
        }
        Ok(())
    }

    /// Reads and handles the message at `offset` (or skips to the data appended there); `false`
    /// at the end of the file.
    fn message_at<R: Read>(
        &mut self,
        r: &mut R,
        offset: &mut u64,
        payload: &mut [u8],
        instance: u8,
        warnings: &mut Vec<Note>,
    ) -> Result<bool, UlogError> {
        if let Some(o) = self.appended.first().copied() {
            if o <= *offset || o - *offset < 3 {
                // The appended data starts here, or inside the next header.
                self.appended.remove(0);
                if o > *offset {
                    return skip_to(r, offset, o, warnings);
                } else if o < *offset {
                    warnings.push(Note::UlogAppendedBehind {
                        appended: o,
                        offset: *offset,
                    });
                }
                return Ok(true);
            }
        }
        let at = *offset;
        let io = |source| UlogError::Io { offset: at, source };
        let mut h = [0u8; 3];
        let size = match read_exact_or_end(r, &mut h) {
            Ok(false) => return Ok(false),
            Ok(true) => u16::from_le_bytes([h[0], h[1]]) as usize,
            Err(e) if e.kind() == std::io::ErrorKind::UnexpectedEof => {
                warnings.push(cut_short(at));
                return Ok(false);
            }
            Err(source) => return Err(io(source)),
        };
        let end = *offset + 3 + size as u64;
        if let Some(o) = self.appended.first().copied().filter(|&o| end > o) {
            // As pyulog reads appended data (`core.py`, `_read_file_data(read_until=offset)`): a
            // message running into it was cut when the logger stopped; it is dropped, and reading
            // goes on where the appended data starts.
            self.appended.remove(0);
            warnings.push(Note::UlogRunsIntoAppended {
                offset: *offset,
                appended: o,
            });
            *offset += 3;
            return skip_to(r, offset, o, warnings);
        }
        match read_exact_or_end(r, &mut payload[..size]) {
            Ok(true) => {}
            Ok(false) if size == 0 => {}
            Ok(false) => {
                warnings.push(cut_short(*offset));
                return Ok(false);
            }
            Err(e) if e.kind() == std::io::ErrorKind::UnexpectedEof => {
                warnings.push(cut_short(*offset));
                return Ok(false);
            }
            Err(source) => return Err(io(source)),
        }
        self.message(h[2], &payload[..size], *offset, instance)?;
        *offset += 3 + size as u64;
        Ok(true)
    }

    /// Handles one message of type `ty` at byte `offset`.
    fn message(&mut self, ty: u8, p: &[u8], offset: u64, instance: u8) -> Result<(), UlogError> {
        match ty {
            b'B' if p.len() >= 16 => {
                let flags = u64::from_le_bytes(p[8..16].try_into().unwrap_or([0; 8]));
                if flags & !1 != 0 {
                    return Err(UlogError::IncompatibleFlags { flags });
                }
                if flags & 1 != 0 && p.len() >= 40 {
                    // Up to three file offsets where data was appended (zero: none).
                    self.appended = p[16..40]
                        .chunks_exact(8)
                        .map(|c| u64::from_le_bytes(c.try_into().unwrap_or([0; 8])))
                        .filter(|&o| o != 0)
                        .collect();
                    self.appended.sort_unstable();
                }
            }
            b'F' => {
                let text = String::from_utf8_lossy(p);
                let Some((name, fields)) = parse_format(&text) else {
                    // A damaged definition of another topic costs that topic; of an IMU topic,
                    // the log (a type it nests is refused where the topic is laid out).
                    let name = text.split_once(':').map_or("", |(n, _)| n);
                    if Topic::from_name(name).is_some() {
                        return Err(UlogError::BadFormat {
                            offset,
                            text: text.chars().take(80).collect(),
                        });
                    }
                    if self.bad_formats.0 == 0 {
                        self.bad_formats.1 = offset;
                    }
                    self.bad_formats.0 += 1;
                    return Ok(());
                };
                if self.formats.len() >= MAX_FORMATS && !self.formats.contains_key(&name) {
                    return Err(UlogError::TooManyFormats);
                }
                let replaced = self.formats.get(&name).map_or((0, 0), |f| size(f));
                let (n, bytes) = size(&fields);
                let kept = (
                    self.fields.0 - replaced.0 + n,
                    self.fields.1 - replaced.1 + bytes,
                );
                // An IMU topic's own definition is always kept (three topics, each bounded by its
                // message's length).
                if (kept.0 > MAX_FIELDS || kept.1 > MAX_FIELD_BYTES)
                    && Topic::from_name(&name).is_none()
                {
                    if self.over_formats.0 == 0 {
                        self.over_formats.1 = offset;
                    }
                    self.over_formats.0 += 1;
                    return Ok(());
                }
                self.fields = kept;
                Arc::make_mut(&mut self.formats).insert(name, fields);
            }
            b'A' if p.len() >= 3 => {
                let multi_id = p[0];
                let msg_id = u16::from_le_bytes([p[1], p[2]]);
                let name = String::from_utf8_lossy(&p[3..]);
                if let Some(topic) = Topic::from_name(name.trim_end_matches('\0')) {
                    self.seen.insert((topic, multi_id));
                    if multi_id == instance {
                        let fields = self.formats.get(topic.name()).cloned().ok_or_else(|| {
                            UlogError::UnknownType {
                                offset,
                                topic: topic.name().into(),
                                ty: topic.name().into(),
                            }
                        })?;
                        let l = layout(topic, &fields, &self.formats, offset)?;
                        Arc::make_mut(&mut self.subscribed).insert(msg_id, l);
                    } else if self.subscribed.contains_key(&msg_id) {
                        Arc::make_mut(&mut self.subscribed).remove(&msg_id);
                    }
                } else if self.subscribed.contains_key(&msg_id) {
                    Arc::make_mut(&mut self.subscribed).remove(&msg_id);
                }
            }
            b'D' if p.len() >= 2 => {
                let msg_id = u16::from_le_bytes([p[0], p[1]]);
                if let Some(l) = self.subscribed.get(&msg_id) {
                    let l = l.clone();
                    self.data(&l, &p[2..], offset)?;
                }
            }
            b'O' if p.len() >= 2 => {
                let ms = u16::from_le_bytes([p[0], p[1]]);
                self.dropouts.push((offset, self.last_t_s, ms));
            }
            // Info, parameters, logging, sync, removal and kinds this reader does not know: a
            // reader skips what it does not know (the format's forward compatibility).
            _ => {}
        }
        Ok(())
    }

    /// One data message of an IMU topic.
    fn data(&mut self, l: &Layout, d: &[u8], offset: u64) -> Result<(), UlogError> {
        if d.len() < l.need {
            return Err(UlogError::ShortData {
                offset,
                topic: l.topic.name().into(),
                len: d.len(),
                need: l.need,
            });
        }
        let us = l.sample_time.unwrap_or(l.time).read(d);
        let t_s = us * 1e-6;
        self.last_t_s = t_s;
        let xyz = l.xyz.map(|p| p.read(d));
        let temp_c = l.temperature.map(|p| p.read(d));
        let too_many =
            |e: TooMany| UlogError::from(ImuError::TooManySamples(l.topic.name().into(), e.0));
        match l.topic {
            Topic::Combined => {
                let rel = l.relative.map_or(0.0, |p| p.read(d));
                if rel != f64::from(RELATIVE_TIMESTAMP_INVALID) {
                    let s = StreamSample {
                        t_s: (us + rel) * 1e-6,
                        v: xyz,
                        temp_c: None,
                    };
                    self.combined_acc.push(s).map_err(too_many)?;
                }
                let gyro = l.gyro.map(|g| g.map(|p| p.read(d))).unwrap_or_default();
                let s = StreamSample {
                    t_s,
                    v: gyro,
                    temp_c: None,
                };
                self.combined_gyro.push(s).map_err(too_many)?;
            }
            Topic::Accel | Topic::Gyro => {
                let stream = if l.topic == Topic::Accel {
                    &mut self.accel
                } else {
                    &mut self.gyro
                };
                let s = StreamSample {
                    t_s,
                    v: xyz,
                    temp_c,
                };
                stream.push(s).map_err(too_many)?;
            }
        }
        Ok(())
    }

    /// The chosen streams paired into a recording, and the dropouts said.
    fn finish(
        mut self,
        instance: u8,
        mut warnings: Vec<Note>,
    ) -> Result<(Recording, Vec<Note>), UlogError> {
        let raw = self.accel.count().min(self.gyro.count());
        let combined = self.combined_gyro.count();
        // The sensors' own topics are preferred (raw, with temperature), but a log often keeps them
        // only at a few samples per second for comparison while sensor_combined runs at the
        // estimator's rate: then the richer topic is the one a calibration can use.
        let raw_is_sparse = raw > 0 && combined > 0 && raw < combined / 2;
        if raw_is_sparse {
            warnings.push(Note::UlogSparseRawTopics { raw, combined });
        }
        let take = std::mem::take;
        let (acc, gyro, from_combined) = if raw > 0 && !raw_is_sparse {
            (take(&mut self.accel), take(&mut self.gyro), false)
        } else if combined > 0 {
            (
                take(&mut self.combined_acc),
                take(&mut self.combined_gyro),
                true,
            )
        } else {
            let seen = self.seen.iter().map(|(t, i)| (t.name(), *i));
            let found = list_instances(
                seen,
                "no sensor_accel, sensor_gyro or sensor_combined topic",
            );
            return Err(ImuError::NoImu {
                instance,
                found,
                hint: "log sensor_accel and sensor_gyro (or sensor_combined)",
                spelling: None,
            }
            .into());
        };
        let (accel, gyro_n) = (acc.count(), gyro.count());
        if acc.rates_hz().is_some() && !from_combined && accel.abs_diff(gyro_n) > accel / 1000 {
            return Err(UlogError::RateForSeparateTopics {
                accel,
                gyro: gyro_n,
            });
        }
        let (mut rec, mut paired) = pair_streams(acc, gyro);
        if from_combined {
            rec.corrected_by = Some("PX4's sensor_combined");
        }
        if let Some(&(offset, t_s, ms)) = self.dropouts.first() {
            let total: u64 = self.dropouts.iter().map(|d| u64::from(d.2)).sum();
            warnings.push(Note::UlogDropouts {
                count: self.dropouts.len(),
                total_ms: total,
                offset,
                t_s,
                ms,
            });
        }
        warnings.append(&mut paired);
        Ok((rec, warnings))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// One rate re-times one stream per message: accelerometer and gyro topics of different counts
    /// (two rates) are refused with it; equal ones, and sensor_combined, are re-timed.
    #[test]
    fn a_rate_for_topics_of_two_rates_is_refused() {
        let fill = |n: usize, hz: f64, rate: Option<f64>| {
            let mut s = Stream::default();
            s.retime(rate);
            for i in 0..n {
                s.push(StreamSample {
                    t_s: i as f64 / hz,
                    v: [0.0, 0.0, -9.8],
                    temp_c: None,
                })
                .unwrap();
            }
            s
        };
        let two_rates = |rate| State {
            accel: fill(800, 400.0, rate),
            gyro: fill(1600, 800.0, rate),
            ..State::default()
        };
        let e = two_rates(Some(400.0)).finish(0, Vec::new()).unwrap_err();
        assert!(
            matches!(
                e,
                UlogError::RateForSeparateTopics {
                    accel: 800,
                    gyro: 1600
                }
            ),
            "{e}"
        );
        assert!(two_rates(None).finish(0, Vec::new()).is_ok());
        let one_rate = State {
            accel: fill(800, 400.0, Some(500.0)),
            gyro: fill(800, 400.0, Some(500.0)),
            ..State::default()
        };
        let (rec, w) = one_rate.finish(0, Vec::new()).unwrap();
        assert!((rec.t_s[799] - rec.t_s[0] - 799.0 / 500.0).abs() < 1e-12);
        assert!(
            w.iter()
                .any(|w| w.to_string().contains("the stamps imply 400.0000 Hz")),
            "{w:?}"
        );
    }

    #[test]
    fn sparse_sensor_topics_give_way_to_sensor_combined() {
        let fill = |n: usize, temp: Option<f64>| {
            let mut s = Stream::default();
            for i in 0..n {
                let t_s = i as f64 * 0.004;
                s.push(StreamSample {
                    t_s,
                    v: [0.0, 0.0, -9.8],
                    temp_c: temp,
                })
                .unwrap();
            }
            s
        };
        let sparse = State {
            accel: fill(6, Some(40.0)),
            gyro: fill(6, Some(40.0)),
            combined_acc: fill(1000, None),
            combined_gyro: fill(1000, None),
            ..State::default()
        };
        let (rec, w) = sparse.finish(0, Vec::new()).unwrap();
        assert!(rec.len() > 900 && rec.temp_c.is_none(), "{}", rec.len());
        assert!(
            w.iter().any(|w| w.to_string().contains("only 6 samples")),
            "{w:?}"
        );
        let full = State {
            accel: fill(800, Some(40.0)),
            gyro: fill(800, Some(40.0)),
            combined_acc: fill(1000, None),
            combined_gyro: fill(1000, None),
            ..State::default()
        };
        let (rec, w) = full.finish(0, Vec::new()).unwrap();
        assert!(rec.len() == 800 && rec.temp_c.is_some(), "{}", rec.len());
        assert!(
            !w.iter().any(|w| w.to_string().contains("sensor_combined")),
            "{w:?}"
        );
    }
}

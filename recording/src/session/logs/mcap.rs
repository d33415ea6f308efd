//! ROS 2 bags in MCAP: the `sensor_msgs/msg/Imu` messages of one topic, timed by each message's
//! `header.stamp` (the driver's sample time; the bag's log time is when the recorder got it).
//!
//! The container is read by Foxglove's `mcap` crate (the format's reference implementation) with its
//! streaming `LinearReader`, every record capped in length (`RECORD_LIMIT`). Chunks come out whole
//! and are decompressed and walked here (`State::chunk`): the crate's own walk of a chunk's records
//! subtracts a record's length from what is left of the chunk unchecked, which overflows on a
//! damaged chunk (our fuzz target found it), so the lengths are checked here instead. The message is decoded by hand ([`decode_imu`]): a CDR
//! decoder crate would be a general serde layer for one fixed message of plain numbers, and the
//! layout is short and fixed by the message definition (`sensor_msgs/msg/Imu.msg`,
//! `std_msgs/msg/Header.msg`, `builtin_interfaces/msg/Time.msg`).

mod cdr;

use super::resume::{join, stretches, Mark, Marker, NO_TIMES};
use super::StreamAt;
use super::{Keep, Stream, StreamSample, TooMany};
use crate::session::import::Recording;
use crate::session::note::Note;
use crate::spelling::{Spelling, UserOption};
use ::mcap::records::Record;
use ::mcap::sans_io::linear_reader::{LinearReadEvent, LinearReader, LinearReaderOptions};
use shared::OutputUnit;
use std::collections::BTreeMap;
use std::fs::File;
use std::io::{BufReader, Read, Seek, SeekFrom};
use std::sync::Arc;

pub use cdr::{decode_imu, CdrError, ImuMessage};

/// The file's first eight bytes.
pub const MAGIC: [u8; 8] = *b"\x89MCAP0\r\n";
/// The longest record accepted, bytes: a whole chunk, compressed or not (writers make chunks of
/// about 1 MiB; an Imu message is about 330 bytes).
pub(crate) const RECORD_LIMIT: usize = 64 << 20;
/// The ROS 2 message type read.
const IMU_SCHEMA: &str = "sensor_msgs/msg/Imu";
/// Most channels remembered (for the listing in an error).
const MAX_CHANNELS: usize = 4096;
/// Longest schema name, topic or encoding remembered, bytes: a ROS 2 name is tens of bytes, and a
/// record up to [`RECORD_LIMIT`] would otherwise be kept [`MAX_CHANNELS`] times over. A schema or
/// channel with a longer one is left out (it is no Imu topic's).
const MAX_NAME: usize = 4096;

/// Why an MCAP file cannot be read.
#[derive(Debug, thiserror::Error)]
pub enum McapError {
    /// Reading failed.
    #[error("read error after byte {offset}")]
    Io {
        /// Bytes read so far.
        offset: u64,
        /// The cause.
        source: std::io::Error,
    },
    /// The container is damaged or not MCAP. The mcap crate's error is said in the middle of the
    /// message (the advice follows it), so it is shown there and not also returned as `source()`.
    #[error(
        "not a readable MCAP file (after byte {offset}): {}; check it with `mcap doctor`",
        shared::chain::Chain(.cause)
    )]
    Container {
        /// Bytes read so far.
        offset: u64,
        /// The mcap crate's error.
        cause: ::mcap::McapError,
    },
    /// No Imu topic.
    #[error(
        "no {IMU_SCHEMA} topic in the bag (its topics: {topics}); record the IMU's topic with \
         `ros2 bag record -s mcap TOPIC`"
    )]
    NoImuTopic {
        /// The topics found, with their types.
        topics: String,
    },
    /// Several Imu topics and none chosen ([`UserOption::Topic`]).
    #[error(
        "the bag has several {IMU_SCHEMA} topics ({topics}): choose one with {}",
        crate::spelling::given_by(*.spelling, UserOption::Topic, "NAME")
    )]
    SeveralImuTopics {
        /// The Imu topics.
        topics: String,
        /// The caller's names of the options: none from the reader, the caller's once spelled.
        spelling: Option<Spelling>,
    },
    /// The topic asked for is not an Imu topic of the bag.
    #[error(
        "{}: not a {IMU_SCHEMA} topic of the bag; its Imu topics: {imu_topics}",
        crate::spelling::given_by(*.spelling, UserOption::Topic, .topic)
    )]
    NoSuchTopic {
        /// The topic asked for.
        topic: String,
        /// The Imu topics there are.
        imu_topics: String,
        /// The caller's names of the options: none from the reader, the caller's once spelled.
        spelling: Option<Spelling>,
    },
    /// Not CDR.
    #[error(
        "topic {topic} is encoded as '{encoding}', not ROS 2's 'cdr': record it with a ROS 2 \
         recorder"
    )]
    Encoding {
        /// The topic.
        topic: String,
        /// Its message encoding.
        encoding: String,
    },
    /// A message that does not decode.
    #[error("topic {topic}, message {index} (from 1): {problem}; the bag is damaged")]
    BadMessage {
        /// The topic.
        topic: String,
        /// Which message.
        index: u64,
        /// What is wrong.
        problem: CdrError,
    },
    /// More samples than are kept at once, from a reader that cannot be read again.
    #[error(
        "more than {0} Imu messages, the most kept in memory at once from a stream that cannot \
         be read a second time: read it from a file"
    )]
    TooManySamples(usize),
    /// A chunk that does not decompress to its stated size, or whose records overrun it.
    #[error(
        "the chunk ending before byte {offset} is damaged ({problem}); check the bag with \
         `mcap doctor`"
    )]
    Chunk {
        /// Bytes read so far.
        offset: u64,
        /// What is wrong.
        problem: String,
    },
}

/// A channel: its topic, schema name and message encoding.
#[derive(Clone, Debug)]
struct Channel {
    topic: String,
    schema: String,
    encoding: String,
}

/// The reader's state.
#[derive(Default)]
struct State {
    /// The schemas and channels by id, shared with the survey's marks until a record changes them.
    schemas: Arc<BTreeMap<u16, String>>,
    channels: Arc<BTreeMap<u16, Channel>>,
    /// The channel read (the topic asked for, or the first Imu channel).
    chosen: Option<u16>,
    acc: Stream,
    gyro: Stream,
    messages: u64,
    unstamped: u64,
    /// Each accelerometer and gyro sample's log time, s: its time when no message has a stamp.
    log_times: [Vec<f64>; 2],
    /// A pass that keeps samples by their time (a survey, a window, an extract): a message without
    /// a stamp, while none before it had one, is kept and timed by its log time at once, as the
    /// bag is timed when no message has a stamp (else all would be at 0, and a bag longer than
    /// the budget could not be cut by time).
    by_log_time: bool,
}

impl McapError {
    /// The error with the options named as `spelling` does (the reader names none).
    pub fn spelled(self, spelling: Spelling) -> McapError {
        match self {
            McapError::SeveralImuTopics { topics, .. } => McapError::SeveralImuTopics {
                topics,
                spelling: Some(spelling),
            },
            McapError::NoSuchTopic {
                topic, imu_topics, ..
            } => McapError::NoSuchTopic {
                topic,
                imu_topics,
                spelling: Some(spelling),
            },
            e => e,
        }
    }
}

/// Reads the Imu messages of `topic` (default: the bag's only Imu topic) from an MCAP file.
pub fn read<R: Read>(r: R, topic: Option<&str>) -> Result<(Recording, Vec<Note>), McapError> {
    read_keeping(r, topic, &Keep::default(), None)
}

/// [`read`], each stream keeping what `keep` says.
pub(crate) fn read_keeping<R: Read>(
    mut r: R,
    topic: Option<&str>,
    keep: &Keep,
    rate_hz: Option<f64>,
) -> Result<(Recording, Vec<Note>), McapError> {
    let mut reader = linear_reader(false);
    let mut st = State::new(keep, rate_hz);
    let mut marker = Marker::for_keep(keep);
    if let Some(m) = marker.as_mut() {
        // After the magic: the first record, read as the survey reads it.
        m.set(MAGIC.len() as u64, st.at(), NO_TIMES, 0);
    }
    let mut offset = 0u64;
    let cut_at = st.records(
        &mut r,
        &mut reader,
        &mut offset,
        topic,
        None,
        marker.as_mut(),
    )?;
    if let (Some(marker), Keep::Survey(report)) = (marker, keep) {
        let resume = Resume {
            marks: marker.finish(st.take_times()),
            last: st.at(),
            cut_at,
        };
        if let Ok(mut r) = report.lock() {
            r.resume = Some(Arc::new(super::resume::Resume::Mcap(resume)));
        }
    }
    let (rec, mut warnings) = st.finish(topic)?;
    warnings.extend(cut_at.map(cut_note));
    Ok((rec, warnings))
}

/// The reader of the file's records, from its start (`resumed`: from a record after it).
fn linear_reader(resumed: bool) -> LinearReader {
    let options = LinearReaderOptions::default()
        .with_record_length_limit(RECORD_LIMIT)
        .with_emit_chunks(true)
        .with_skip_start_magic(resumed);
    LinearReader::new_with_options(options)
}

/// A file cut short at byte `offset`, said.
fn cut_note(offset: u64) -> Note {
    Note::McapCutShort { offset }
}

/// The reader's state at a mark, or at the end of the survey (`super::resume`).
#[derive(Clone, Debug)]
pub(crate) struct At {
    schemas: Arc<BTreeMap<u16, String>>,
    channels: Arc<BTreeMap<u16, Channel>>,
    chosen: Option<u16>,
    messages: u64,
    unstamped: u64,
    streams: [StreamAt; 2],
}

/// What a survey of a bag leaves for the windows' passes (`super::resume`): its marks, its state
/// at the end of the file, and where the file was cut short.
#[derive(Debug)]
pub(crate) struct Resume {
    marks: Vec<Mark<At>>,
    last: At,
    cut_at: Option<u64>,
}

/// One window of a long bag (`keep`, a [`Keep::Span`]) read from the stretches of `file` its
/// samples lie in, as the survey's `resume` marks them (`super::resume`): the same samples and
/// words as [`read_keeping`] reading the whole file with `keep`.
pub(crate) fn read_window(
    file: &mut File,
    resume: &Resume,
    topic: Option<&str>,
    keep: &Keep,
    rate_hz: Option<f64>,
) -> Result<(Recording, Vec<Note>), McapError> {
    let mut st = State::new(keep, rate_hz);
    let (lo, hi) = keep.reach();
    for (i, end) in stretches(&resume.marks, lo, hi) {
        let mark = &resume.marks[i];
        let mut offset = mark.offset;
        file.seek(SeekFrom::Start(offset))
            .map_err(|source| McapError::Io { offset, source })?;
        let mut r = BufReader::with_capacity(1 << 20, &mut *file);
        st.resume(&mark.state);
        let mut reader = linear_reader(true);
        st.records(&mut r, &mut reader, &mut offset, topic, end, None)?;
    }
    st.resume(&resume.last);
    let (rec, mut warnings) = st.finish(topic)?;
    warnings.extend(resume.cut_at.map(cut_note));
    Ok((rec, warnings))
}

fn read_some<R: Read>(r: &mut R, buf: &mut [u8]) -> std::io::Result<usize> {
    loop {
        match r.read(buf) {
            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => {}
            other => return other,
        }
    }
}

impl State {
    /// Empty streams that keep what `keep` says, re-timed at `rate_hz` (none: as stamped).
    fn new(keep: &Keep, rate_hz: Option<f64>) -> State {
        let mut st = State {
            acc: Stream::new(keep),
            gyro: Stream::new(keep),
            by_log_time: !matches!(keep, Keep::All { .. }),
            ..State::default()
        };
        st.acc.retime(rate_hz);
        st.gyro.retime(rate_hz);
        st
    }

    /// Where the reader stands ([`At`]).
    fn at(&self) -> At {
        At {
            schemas: Arc::clone(&self.schemas),
            channels: Arc::clone(&self.channels),
            chosen: self.chosen,
            messages: self.messages,
            unstamped: self.unstamped,
            streams: [self.acc.at(), self.gyro.at()],
        }
    }

    /// Goes on from `at`.
    fn resume(&mut self, at: &At) {
        self.schemas = Arc::clone(&at.schemas);
        self.channels = Arc::clone(&at.channels);
        self.chosen = at.chosen;
        self.messages = at.messages;
        self.unstamped = at.unstamped;
        self.acc.resume(&at.streams[0]);
        self.gyro.resume(&at.streams[1]);
    }

    /// The samples read, both streams told.
    fn read(&self) -> usize {
        self.acc.count() + self.gyro.count()
    }

    /// A survey: the least and greatest time of the samples read since the last call.
    fn take_times(&mut self) -> (f64, f64) {
        join(self.acc.take_times(), self.gyro.take_times())
    }

    /// Reads the records of `r` (at the file's byte `offset`) with `reader` up to the byte `end`
    /// (`None`: the end of the file), setting `marker`'s marks on the way; where the file is cut
    /// short inside a record, the byte it ends at.
    fn records<R: Read>(
        &mut self,
        r: &mut R,
        reader: &mut LinearReader,
        offset: &mut u64,
        topic: Option<&str>,
        end: Option<u64>,
        mut marker: Option<&mut Marker<At>>,
    ) -> Result<Option<u64>, McapError> {
        while let Some(event) = reader.next_event() {
            let event = match event {
                // A recorder that stopped (a crash, a full disk) leaves its last record cut: what
                // came before it is sound, and the cut record (a whole chunk, if chunked) is what
                // is lost.
                Err(::mcap::McapError::UnexpectedEof) if self.messages > 0 => {
                    return Ok(Some(*offset))
                }
                other => other.map_err(|source| McapError::Container {
                    offset: *offset,
                    cause: source,
                })?,
            };
            match event {
                LinearReadEvent::ReadRequest(need) => {
                    let buf = reader.insert(need.min(RECORD_LIMIT));
                    let n = read_some(r, buf).map_err(|source| McapError::Io {
                        offset: *offset,
                        source,
                    })?;
                    *offset += n as u64;
                    reader.notify_read(n);
                }
                LinearReadEvent::Record { data, opcode } => {
                    let record = ::mcap::parse_record(opcode, data).map_err(|source| {
                        McapError::Container {
                            offset: *offset,
                            cause: source,
                        }
                    })?;
                    match record {
                        Record::Chunk { header, data } => {
                            self.chunk(&header, &data, topic, *offset)?
                        }
                        other => self.record(other, topic)?,
                    }
                    // The reader asks for no byte beyond the record it reads: the next begins
                    // at `offset`.
                    if end.is_some_and(|e| *offset >= e) {
                        return Ok(None);
                    }
                    if let Some(m) = marker.as_deref_mut().filter(|m| m.due(self.read())) {
                        let times = self.take_times();
                        m.set(*offset, self.at(), times, self.read());
                    }
                }
            }
        }
        Ok(None)
    }

    /// A chunk: decompressed (no more than its stated size, itself within [`RECORD_LIMIT`]) and its
    /// records (opcode, `u64` length, body) read in turn.
    fn chunk(
        &mut self,
        header: &::mcap::records::ChunkHeader,
        data: &[u8],
        topic: Option<&str>,
        offset: u64,
    ) -> Result<(), McapError> {
        let bad = |problem: String| McapError::Chunk { offset, problem };
        let size = usize::try_from(header.uncompressed_size)
            .ok()
            .filter(|&n| n <= RECORD_LIMIT)
            .ok_or_else(|| bad(format!("{} bytes uncompressed", header.uncompressed_size)))?;
        let owned;
        let body: &[u8] = match header.compression.as_str() {
            "" => data,
            "zstd" => {
                owned = zstd::bulk::decompress(data, size)
                    .map_err(|e| bad(shared::chain::Chain(&e).to_string()))?;
                &owned
            }
            "lz4" => {
                let mut out = Vec::new();
                let decoder = lz4::Decoder::new(data)
                    .map_err(|e| bad(shared::chain::Chain(&e).to_string()))?;
                decoder
                    .take(size as u64 + 1)
                    .read_to_end(&mut out)
                    .map_err(|e| bad(shared::chain::Chain(&e).to_string()))?;
                owned = out;
                &owned
            }
            other => return Err(bad(format!("compression '{other}' is not zstd or lz4"))),
        };
        if body.len() != size {
            return Err(bad(format!(
                "{} bytes where the chunk says {size}",
                body.len()
            )));
        }
        let mut pos = 0usize;
        while pos < body.len() {
            let head = body
                .get(pos..pos + 9)
                .ok_or_else(|| bad("a cut record".into()))?;
            let len = u64::from_le_bytes(std::array::from_fn(|k| head[1 + k]));
            let end = usize::try_from(len)
                .ok()
                .and_then(|n| (pos + 9).checked_add(n))
                .filter(|&e| e <= body.len())
                .ok_or_else(|| bad(format!("a record of {len} bytes overruns it")))?;
            let record = ::mcap::parse_record(head[0], &body[pos + 9..end]).map_err(|source| {
                McapError::Container {
                    offset,
                    cause: source,
                }
            })?;
            self.record(record, topic)?;
            pos = end;
        }
        Ok(())
    }

    fn record(&mut self, record: Record<'_>, topic: Option<&str>) -> Result<(), McapError> {
        match record {
            Record::Schema { header, .. } if header.name.len() > MAX_NAME => {}
            Record::Channel(c) if c.topic.len().max(c.message_encoding.len()) > MAX_NAME => {}
            Record::Schema { header, .. } if self.schemas.len() < MAX_CHANNELS => {
                Arc::make_mut(&mut self.schemas).insert(header.id, header.name);
            }
            Record::Channel(c) if self.channels.len() < MAX_CHANNELS => {
                let schema = self.schemas.get(&c.schema_id).cloned().unwrap_or_default();
                let ch = Channel {
                    topic: c.topic,
                    schema,
                    encoding: c.message_encoding,
                };
                let wanted = ch.schema == IMU_SCHEMA
                    && topic.is_none_or(|t| t == ch.topic)
                    && self.chosen.is_none();
                if wanted {
                    if ch.encoding != "cdr" {
                        return Err(McapError::Encoding {
                            topic: ch.topic,
                            encoding: ch.encoding,
                        });
                    }
                    self.chosen = Some(c.id);
                }
                Arc::make_mut(&mut self.channels).insert(c.id, ch);
            }
            Record::Message { header, data } if Some(header.channel_id) == self.chosen => {
                self.messages += 1;
                let m = decode_imu(&data).map_err(|problem| McapError::BadMessage {
                    topic: self.channels[&header.channel_id].topic.clone(),
                    index: self.messages,
                    problem,
                })?;
                // A stamp of 0 is a driver that stamps nothing only when every message has it; a
                // bag recorded in simulated time starts at 0 and goes on from there.
                if m.stamp_s == 0.0 {
                    self.unstamped += 1;
                }
                let log_s = header.log_time as f64 * 1e-9;
                // The log times are needed only while no message has had a stamp.
                let all_unstamped = self.unstamped == self.messages;
                let t_s = match self.by_log_time && all_unstamped {
                    true => log_s,
                    false => m.stamp_s,
                };
                let too_many = |e: TooMany| McapError::TooManySamples(e.0);
                let s = |v| StreamSample {
                    t_s,
                    v,
                    temp_c: None,
                };
                if !all_unstamped && !self.log_times[0].is_empty() {
                    self.log_times = Default::default();
                }
                for (k, (st, v)) in [(&mut self.acc, m.acc_m_s2), (&mut self.gyro, m.gyro_rad_s)]
                    .into_iter()
                    .enumerate()
                {
                    let before = st.samples.len();
                    st.push(s(v)).map_err(too_many)?;
                    if st.samples.len() > before && all_unstamped {
                        self.log_times[k].push(log_s);
                    }
                }
            }
            _ => {}
        }
        Ok(())
    }

    fn finish(mut self, topic: Option<&str>) -> Result<(Recording, Vec<Note>), McapError> {
        let imu: Vec<&str> = self
            .channels
            .values()
            .filter(|c| c.schema == IMU_SCHEMA)
            .map(|c| c.topic.as_str())
            .collect();
        let list = |v: &[&str]| {
            if v.is_empty() {
                "none".to_string()
            } else {
                v.join(", ")
            }
        };
        match (topic, self.chosen) {
            (Some(t), None) => {
                return Err(McapError::NoSuchTopic {
                    topic: t.to_string(),
                    imu_topics: list(&imu),
                    spelling: None,
                })
            }
            (None, None) => {
                let all: Vec<String> = self
                    .channels
                    .values()
                    .map(|c| format!("{} ({})", c.topic, c.schema))
                    .collect();
                let all: Vec<&str> = all.iter().map(String::as_str).collect();
                return Err(McapError::NoImuTopic { topics: list(&all) });
            }
            (None, Some(_)) if imu.len() > 1 => {
                return Err(McapError::SeveralImuTopics {
                    topics: list(&imu),
                    spelling: None,
                })
            }
            _ => {}
        }
        let unstamped = self.unstamped > 0 && self.unstamped == self.messages;
        if unstamped {
            for (st, log) in [&mut self.acc, &mut self.gyro]
                .into_iter()
                .zip(&self.log_times)
            {
                for (s, &t) in st.samples.iter_mut().zip(log) {
                    s.t_s = t;
                }
            }
        }
        let (mut rec, mut warnings) = super::pair(self.acc, self.gyro, f64::INFINITY);
        rec.acc_unit = Some(OutputUnit::MetresPerSecondSquared);
        if unstamped {
            warnings.insert(
                0,
                Note::McapUnstamped {
                    count: self.unstamped,
                },
            );
        }
        Ok((rec, warnings))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A hand-assembled Imu message: frame id "base" (length 5 with its NUL) ends at body offset 17,
    /// so the first double starts at 24 after 7 bytes of padding.
    fn message(little: bool) -> Vec<u8> {
        let mut b: Vec<u8> = vec![0, u8::from(little), 0, 0];
        let u32b = |v: u32| {
            if little {
                v.to_le_bytes()
            } else {
                v.to_be_bytes()
            }
        };
        let f64b = |v: f64| {
            if little {
                v.to_le_bytes()
            } else {
                v.to_be_bytes()
            }
        };
        b.extend(u32b(12));
        b.extend(u32b(500_000_000));
        b.extend(u32b(5));
        b.extend(b"base\0");
        b.extend([0; 7]);
        let values: Vec<f64> = (0..40).map(f64::from).collect();
        for v in values {
            b.extend(f64b(v));
        }
        b
    }

    #[test]
    fn an_imu_message_decodes_in_either_byte_order_with_its_padding() {
        for little in [true, false] {
            let m = decode_imu(&message(little)).unwrap();
            assert_eq!(m.stamp_s, 12.5);
            // orientation 0..3, its covariance 4..12, angular velocity 13..15.
            assert_eq!(m.gyro_rad_s, [13.0, 14.0, 15.0]);
            assert_eq!(m.acc_m_s2, [25.0, 26.0, 27.0]);
        }
        let m = message(true);
        let e = decode_imu(&m[..m.len() - 8 * 13]).unwrap_err();
        assert!(
            matches!(
                e,
                CdrError::Short {
                    field: "linear_acceleration",
                    ..
                }
            ),
            "{e}"
        );
        let mut xcdr2 = message(true);
        xcdr2[1] = 0x07;
        assert_eq!(decode_imu(&xcdr2), Err(CdrError::Encapsulation(7)));
    }
}

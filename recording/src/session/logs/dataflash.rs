//! ArduPilot DataFlash logs (`.bin`): the IMU's samples from the `IMU` messages (the accelerometer in
//! m/s², the gyro in rad/s, the sensor's temperature `T`; instance `I`, or `IMU2`/`IMU3` in older
//! logs), else from `ACC` + `GYR` (the raw batch-sampler messages, instance `I`).
//!
//! Written against ArduPilot's `libraries/AP_Logger/LogStructure.h` (the `FMT` message and the
//! format characters) with pymavlink's `DFReader.py` (`DFReader_binary`, v2.4) as the reference
//! reader: every message is `0xA3 0x95 type payload`, its length and field types given by an earlier
//! `FMT` message (type 128: Type, Length, Name `char[4]`, Format `char[16]`, Columns `char[64]`).
//! Like pymavlink, bytes that do not start a known message are skipped (logs often have damage and
//! garbage at the end), and the skipped bytes are reported. Why our own reader: no Rust crate reads
//! DataFlash logs in a maintained form; a message is at most 255 bytes (its length is a `u8`), so the
//! reader streams with a window of a few hundred bytes.

use super::resume::{stretches, Mark, Marker};
use super::stream::{read_by, take_times_of};
use super::vehicle::VehicleParams;
use super::{
    list_instances, pair_streams, ImuError, Keep, Stream, StreamAt, StreamSample, TooMany,
};
use crate::session::import::Recording;
use crate::session::note::Note;
use crate::spelling::Spelling;
use std::fs::File;
use std::io::{Read, Seek, SeekFrom};
use std::sync::Arc;

/// A log's first bytes: the header and the type of the `FMT` message that defines `FMT`.
pub const MAGIC: [u8; 3] = [HEAD1, HEAD2, FMT_TYPE];
const HEAD1: u8 = 0xA3;
const HEAD2: u8 = 0x95;
const FMT_TYPE: u8 = 0x80;
/// The `FMT` message's length: 3 header bytes, Type, Length, Name[4], Format[16], Columns[64].
const FMT_LEN: usize = 89;

mod parm;

/// Why a DataFlash log cannot be read; each names the byte offset where it went wrong.
#[derive(Debug, thiserror::Error)]
pub enum DataFlashError {
    /// Reading failed.
    #[error("read error at byte {offset}")]
    Io {
        /// Where.
        offset: u64,
        /// The cause.
        source: std::io::Error,
    },
    /// A `FMT` message this reader cannot use for an IMU message.
    #[error(
        "byte {offset}: the format of '{name}' ('{format}', length {length}) does not add up: the \
         log is damaged; pymavlink's mavlogdump.py shows how far it reads"
    )]
    BadFormat {
        /// Where.
        offset: u64,
        /// The message name.
        name: String,
        /// Its format characters.
        format: String,
        /// Its stated length.
        length: u8,
    },
    /// No IMU for the instance, or too many samples.
    #[error(transparent)]
    Imu(#[from] ImuError),
}

/// A message format: name, length, and the byte offset and type of each column.
#[derive(Clone, Debug)]
struct Format {
    name: String,
    length: usize,
    columns: Vec<(String, usize, u8)>,
}

impl Format {
    /// Parses the body of a `FMT` message (after the 3 header bytes).
    fn parse(body: &[u8]) -> Option<(u8, Format, String)> {
        let text = |b: &[u8]| {
            let end = b.iter().position(|&c| c == 0).unwrap_or(b.len());
            String::from_utf8_lossy(&b[..end]).trim().to_string()
        };
        let ty = body[0];
        let length = body[1] as usize;
        let name = text(&body[2..6]);
        let chars = text(&body[6..22]);
        let names = text(&body[22..86]);
        let mut columns = Vec::new();
        let mut offset = 3usize;
        let mut names_it = names.split(',');
        for c in chars.bytes() {
            let size = char_size(c)?;
            columns.push((names_it.next().unwrap_or("").to_string(), offset, c));
            offset += size;
        }
        if offset != length {
            return None;
        }
        Some((
            ty,
            Format {
                name,
                length,
                columns,
            },
            chars,
        ))
    }

    fn column(&self, name: &str) -> Option<(usize, u8)> {
        self.columns
            .iter()
            .find(|c| c.0 == name)
            .map(|c| (c.1, c.2))
    }
}

/// The size of a format character (`LogStructure.h`'s table; pymavlink's `FORMAT_TO_STRUCT`).
fn char_size(c: u8) -> Option<usize> {
    Some(match c {
        b'b' | b'B' | b'M' => 1,
        b'h' | b'H' | b'c' | b'C' | b'g' => 2,
        b'i' | b'I' | b'f' | b'e' | b'E' | b'L' | b'n' => 4,
        b'q' | b'Q' | b'd' => 8,
        b'N' => 16,
        b'Z' | b'a' => 64,
        _ => return None,
    })
}

/// A number field at `off` of type `c` in `m` (scaled as pymavlink scales it).
fn number(m: &[u8], off: usize, c: u8) -> Option<f64> {
    let b = |n: usize| m.get(off..off + n);
    Some(match c {
        b'b' | b'M' => f64::from(b(1)?[0] as i8),
        b'B' => f64::from(b(1)?[0]),
        b'h' => f64::from(i16::from_le_bytes(b(2)?.try_into().ok()?)),
        b'H' => f64::from(u16::from_le_bytes(b(2)?.try_into().ok()?)),
        b'c' => f64::from(i16::from_le_bytes(b(2)?.try_into().ok()?)) * 0.01,
        b'C' => f64::from(u16::from_le_bytes(b(2)?.try_into().ok()?)) * 0.01,
        b'i' => f64::from(i32::from_le_bytes(b(4)?.try_into().ok()?)),
        b'I' => f64::from(u32::from_le_bytes(b(4)?.try_into().ok()?)),
        b'e' => f64::from(i32::from_le_bytes(b(4)?.try_into().ok()?)) * 0.01,
        b'E' => f64::from(u32::from_le_bytes(b(4)?.try_into().ok()?)) * 0.01,
        b'L' => f64::from(i32::from_le_bytes(b(4)?.try_into().ok()?)) * 1e-7,
        b'f' => f64::from(f32::from_le_bytes(b(4)?.try_into().ok()?)),
        b'd' => f64::from_le_bytes(b(8)?.try_into().ok()?),
        b'q' => i64::from_le_bytes(b(8)?.try_into().ok()?) as f64,
        b'Q' => u64::from_le_bytes(b(8)?.try_into().ok()?) as f64,
        _ => return None,
    })
}

/// The IMU messages read.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Kind {
    /// `IMU` (instance `I`) or `IMU`/`IMU2`/`IMU3`.
    Imu,
    /// `ACC`.
    Acc,
    /// `GYR`.
    Gyr,
}

/// Where an IMU message's values are.
#[derive(Clone, Debug)]
struct Layout {
    kind: Kind,
    /// Time column and its scale to seconds.
    time: (usize, u8, f64),
    /// The instance column, or the instance its name gives.
    instance: Result<(usize, u8), u8>,
    acc: Option<[(usize, u8); 3]>,
    gyro: Option<[(usize, u8); 3]>,
    temperature: Option<(usize, u8)>,
}

/// The layout of an IMU message format, `None` for every other message.
fn layout(f: &Format) -> Option<Layout> {
    let (kind, name_instance) = match f.name.as_str() {
        "IMU" => (Kind::Imu, 0),
        "IMU2" => (Kind::Imu, 1),
        "IMU3" => (Kind::Imu, 2),
        "ACC" => (Kind::Acc, 0),
        "GYR" => (Kind::Gyr, 0),
        "ACC1" | "GYR1" | "ACC2" | "GYR2" | "ACC3" | "GYR3" => {
            let k = if f.name.starts_with("ACC") {
                Kind::Acc
            } else {
                Kind::Gyr
            };
            (k, f.name.as_bytes()[3] - b'1')
        }
        _ => return None,
    };
    let three = |p: &str| -> Option<[(usize, u8); 3]> {
        Some([
            f.column(&format!("{p}X"))?,
            f.column(&format!("{p}Y"))?,
            f.column(&format!("{p}Z"))?,
        ])
    };
    let time = f
        .column("SampleUS")
        .or_else(|| f.column("TimeUS"))
        .map(|(o, c)| (o, c, 1e-6))
        .or_else(|| f.column("TimeMS").map(|(o, c)| (o, c, 1e-3)))?;
    Some(Layout {
        kind,
        time,
        instance: f.column("I").ok_or(name_instance),
        acc: if kind == Kind::Gyr {
            None
        } else {
            Some(three("Acc")?)
        },
        gyro: if kind == Kind::Acc {
            None
        } else {
            Some(three("Gyr")?)
        },
        temperature: f.column("T").filter(|_| kind == Kind::Imu),
    })
}

/// A streaming window over the log: at most a message's worth is looked ahead.
struct Window<R> {
    r: R,
    buf: Vec<u8>,
    start: usize,
    /// The file offset of `buf[start]`.
    offset: u64,
    eof: bool,
}

impl<R: Read> Window<R> {
    /// Makes `n` bytes available if the file has them; returns how many are.
    fn fill(&mut self, n: usize) -> Result<usize, DataFlashError> {
        while self.buf.len() - self.start < n && !self.eof {
            if self.start > 0 {
                self.buf.drain(..self.start);
                self.start = 0;
            }
            let old = self.buf.len();
            self.buf.resize(old + 64 * 1024, 0);
            let got = loop {
                match self.r.read(&mut self.buf[old..]) {
                    Ok(k) => break k,
                    Err(e) if e.kind() == std::io::ErrorKind::Interrupted => {}
                    Err(source) => {
                        return Err(DataFlashError::Io {
                            offset: self.offset,
                            source,
                        })
                    }
                }
            };
            self.buf.truncate(old + got);
            self.eof = got == 0;
        }
        Ok((self.buf.len() - self.start).min(n))
    }

    fn peek(&self) -> &[u8] {
        &self.buf[self.start..]
    }

    fn consume(&mut self, n: usize) {
        self.start += n;
        self.offset += n as u64;
    }
}

/// The streams gathered and the damage skipped.
#[derive(Default)]
struct State {
    /// The formats by type, shared with the survey's marks until a `FMT` changes them.
    formats: Arc<Vec<Option<Format>>>,
    layouts: Arc<Vec<Option<Layout>>>,
    seen: std::collections::BTreeSet<(&'static str, u8)>,
    imu_acc: Stream,
    imu_gyro: Stream,
    acc: Stream,
    gyro: Stream,
    skipped: u64,
    first_skip: Option<u64>,
    params: VehicleParams,
}

/// The reader's state at a mark (`super::resume`): the formats and each stream's counts.
#[derive(Clone, Debug)]
pub(crate) struct At {
    formats: Arc<Vec<Option<Format>>>,
    layouts: Arc<Vec<Option<Layout>>>,
    streams: [StreamAt; 4],
}

/// What a survey of a DataFlash log leaves for the windows' passes (`super::resume`): its marks,
/// and what it found in the whole file.
#[derive(Debug)]
pub(crate) struct Resume {
    marks: Vec<Mark<At>>,
    streams: [StreamAt; 4],
    seen: std::collections::BTreeSet<(&'static str, u8)>,
    skipped: u64,
    first_skip: Option<u64>,
    params: VehicleParams,
    warnings: Vec<Note>,
}

impl DataFlashError {
    /// The error with the options named as `spelling` does (the reader says flags).
    pub fn spelled(self, spelling: Spelling) -> DataFlashError {
        match self {
            DataFlashError::Imu(e) => DataFlashError::Imu(e.spelled(spelling)),
            e => e,
        }
    }
}

/// Reads the IMU samples of `instance` from a DataFlash log.
pub fn read<R: Read>(r: R, instance: u8) -> Result<(Recording, Vec<Note>), DataFlashError> {
    read_keeping(r, instance, &Keep::default())
}

/// [`read`], each stream keeping what `keep` says.
pub(crate) fn read_keeping<R: Read>(
    r: R,
    instance: u8,
    keep: &Keep,
) -> Result<(Recording, Vec<Note>), DataFlashError> {
    read_with_params(r, instance, keep, None).map(|(rec, w, _)| (rec, w))
}

/// [`read_keeping`], with the vehicle's parameters the log holds (its `PARM` messages).
pub(crate) fn read_with_params<R: Read>(
    r: R,
    instance: u8,
    keep: &Keep,
    rate_hz: Option<f64>,
) -> Result<(Recording, Vec<Note>, VehicleParams), DataFlashError> {
    let mut w = Window::at(r, 0);
    let mut st = State::new(keep, rate_hz);
    let mut warnings = Vec::new();
    let mut marker = Marker::for_keep(keep);
    st.messages(&mut w, instance, None, marker.as_mut(), &mut warnings)?;
    if let Some(first) = st.first_skip {
        warnings.push(Note::DataFlashSkipped {
            count: st.skipped,
            first,
        });
    }
    if let (Some(marker), Keep::Survey(report)) = (marker, keep) {
        let resume = Resume {
            marks: marker.finish(st.take_times()),
            streams: st.streams().map(|s| s.at()),
            seen: st.seen.clone(),
            skipped: st.skipped,
            first_skip: st.first_skip,
            params: st.params.clone(),
            warnings: warnings.clone(),
        };
        if let Ok(mut r) = report.lock() {
            r.resume = Some(Arc::new(super::resume::Resume::DataFlash(resume)));
        }
    }
    let params = std::mem::take(&mut st.params);
    st.finish(instance, warnings)
        .map(|(rec, w)| (rec, w, params))
}

/// One window of a long log (`keep`, a [`Keep::Span`]) read from the stretches of `file` its
/// samples lie in, as the survey's `resume` marks them (`super::resume`): the same samples and
/// words as [`read_with_params`] reading the whole file with `keep`.
pub(crate) fn read_window(
    file: &mut File,
    resume: &Resume,
    instance: u8,
    keep: &Keep,
    rate_hz: Option<f64>,
) -> Result<(Recording, Vec<Note>, VehicleParams), DataFlashError> {
    let mut st = State::new(keep, rate_hz);
    let (lo, hi) = keep.reach();
    for (i, end) in stretches(&resume.marks, lo, hi) {
        let mark = &resume.marks[i];
        file.seek(SeekFrom::Start(mark.offset))
            .map_err(|source| DataFlashError::Io {
                offset: mark.offset,
                source,
            })?;
        let mut w = Window::at(&mut *file, mark.offset);
        st.formats = Arc::clone(&mark.state.formats);
        st.layouts = Arc::clone(&mark.state.layouts);
        for (s, at) in st.streams_mut().into_iter().zip(&mark.state.streams) {
            s.resume(at);
        }
        st.messages(&mut w, instance, end, None, &mut Vec::new())?;
    }
    for (s, at) in st.streams_mut().into_iter().zip(&resume.streams) {
        s.resume(at);
    }
    st.seen = resume.seen.clone();
    (st.skipped, st.first_skip) = (resume.skipped, resume.first_skip);
    let params = resume.params.clone();
    st.finish(instance, resume.warnings.clone())
        .map(|(rec, w)| (rec, w, params))
}

impl<R: Read> Window<R> {
    /// A window over `r`, whose first byte is the file's byte `offset`.
    fn at(r: R, offset: u64) -> Window<R> {
        Window {
            r,
            buf: Vec::new(),
            start: 0,
            offset,
            eof: false,
        }
    }
}

impl State {
    /// Empty streams that keep what `keep` says, re-timed at `rate_hz` (none: as stamped).
    fn new(keep: &Keep, rate_hz: Option<f64>) -> State {
        let mut st = State {
            formats: Arc::new(vec![None; 256]),
            layouts: Arc::new(vec![None; 256]),
            imu_acc: Stream::new(keep),
            imu_gyro: Stream::new(keep),
            acc: Stream::new(keep),
            gyro: Stream::new(keep),
            ..State::default()
        };
        for s in st.streams_mut() {
            s.retime(rate_hz);
        }
        st
    }

    fn streams(&self) -> [&Stream; 4] {
        [&self.imu_acc, &self.imu_gyro, &self.acc, &self.gyro]
    }

    fn streams_mut(&mut self) -> [&mut Stream; 4] {
        [
            &mut self.imu_acc,
            &mut self.imu_gyro,
            &mut self.acc,
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

    /// Reads the messages from where `w` stands up to the byte `end` (`None`: the end of the
    /// file), setting `marker`'s marks on the way.
    fn messages<R: Read>(
        &mut self,
        w: &mut Window<R>,
        instance: u8,
        end: Option<u64>,
        mut marker: Option<&mut Marker<At>>,
        warnings: &mut Vec<Note>,
    ) -> Result<(), DataFlashError> {
        loop {
            if end.is_some_and(|e| w.offset >= e) {
                break;
            }
            if let Some(m) = marker.as_deref_mut().filter(|m| m.due(self.read())) {
                let at = At {
                    formats: Arc::clone(&self.formats),
                    layouts: Arc::clone(&self.layouts),
                    streams: self.streams().map(|s| s.at()),
                };
                let times = self.take_times();
                m.set(w.offset, at, times, self.read());
            }
            let have = w.fill(3)?;
            if have < 3 {
                // One or two bytes left: a message cut short within its header when they begin
                // as one, else bytes that start no message.
                let h = w.peek();
                if have > 0 && h[0] == HEAD1 && (have == 1 || h[1] == HEAD2) {
                    warnings.push(Note::LastMessageCutShort { offset: w.offset });
                } else if have > 0 {
                    self.skipped += have as u64;
                    self.first_skip.get_or_insert(w.offset);
                }
                break;
            }
            let h = w.peek();
            let ty = h[2];
            let length = if ty == FMT_TYPE {
                Some(FMT_LEN)
            } else {
                self.formats[ty as usize].as_ref().map(|f| f.length)
            };
            let Some(length) = length.filter(|_| h[0] == HEAD1 && h[1] == HEAD2) else {
                self.skipped += 1;
                self.first_skip.get_or_insert(w.offset);
                w.consume(1);
                continue;
            };
            if w.fill(length)? < length {
                warnings.push(Note::LastMessageCutShort { offset: w.offset });
                break;
            }
            let offset = w.offset;
            let m = w.peek()[..length].to_vec();
            self.message(ty, &m, offset, instance)?;
            w.consume(length);
        }
        Ok(())
    }

    fn message(
        &mut self,
        ty: u8,
        m: &[u8],
        offset: u64,
        instance: u8,
    ) -> Result<(), DataFlashError> {
        if ty == FMT_TYPE {
            let body = &m[3..];
            let Some((t, f, _)) = Format::parse(body) else {
                // A FMT that does not add up defines nothing usable; an IMU message it was meant
                // for is then an error, any other is skipped like pymavlink does.
                let name = String::from_utf8_lossy(&body[2..6])
                    .trim_end_matches('\0')
                    .to_string();
                if matches!(name.as_str(), "IMU" | "IMU2" | "IMU3" | "ACC" | "GYR") {
                    return Err(DataFlashError::BadFormat {
                        offset,
                        name,
                        format: String::from_utf8_lossy(&body[6..22])
                            .trim_end_matches('\0')
                            .to_string(),
                        length: body[1],
                    });
                }
                return Ok(());
            };
            if t != FMT_TYPE {
                Arc::make_mut(&mut self.layouts)[t as usize] = layout(&f);
                Arc::make_mut(&mut self.formats)[t as usize] = Some(f);
            }
            return Ok(());
        }
        if let Some(f) = self.formats[ty as usize]
            .as_ref()
            .filter(|f| f.name == "PARM")
        {
            parm::record(f, m, &mut self.params);
            return Ok(());
        }
        let Some(l) = self.layouts[ty as usize].clone() else {
            return Ok(());
        };
        self.sample(&l, m, instance)
    }

    fn sample(&mut self, l: &Layout, m: &[u8], instance: u8) -> Result<(), DataFlashError> {
        let get = |(o, c): (usize, u8)| number(m, o, c).unwrap_or(f64::NAN);
        let i = match l.instance {
            Ok(col) => get(col) as u8,
            Err(i) => i,
        };
        let name = match l.kind {
            Kind::Imu => "IMU",
            Kind::Acc => "ACC",
            Kind::Gyr => "GYR",
        };
        if self.seen.len() < 64 {
            self.seen.insert((name, i));
        }
        if i != instance {
            return Ok(());
        }
        let t_s = get((l.time.0, l.time.1)) * l.time.2;
        let temp_c = l.temperature.map(get);
        let too_many =
            |e: TooMany| DataFlashError::from(ImuError::TooManySamples(name.into(), e.0));
        let sample = |v: [(usize, u8); 3]| StreamSample {
            t_s,
            v: v.map(get),
            temp_c,
        };
        match l.kind {
            Kind::Imu => {
                if let (Some(a), Some(g)) = (l.acc, l.gyro) {
                    self.imu_acc.push(sample(a)).map_err(too_many)?;
                    self.imu_gyro.push(sample(g)).map_err(too_many)?;
                }
            }
            Kind::Acc => {
                if let Some(a) = l.acc {
                    self.acc.push(sample(a)).map_err(too_many)?;
                }
            }
            Kind::Gyr => {
                if let Some(g) = l.gyro {
                    self.gyro.push(sample(g)).map_err(too_many)?;
                }
            }
        }
        Ok(())
    }

    fn finish(
        self,
        instance: u8,
        mut warnings: Vec<Note>,
    ) -> Result<(Recording, Vec<Note>), DataFlashError> {
        let (acc, gyro) = if self.imu_acc.count() > 0 {
            (self.imu_acc, self.imu_gyro)
        } else if self.acc.count() > 0 && self.gyro.count() > 0 {
            (self.acc, self.gyro)
        } else {
            let seen = self.seen.iter().copied();
            let found = list_instances(seen, "no IMU, ACC or GYR message");
            return Err(ImuError::NoImu {
                instance,
                found,
                hint: "log IMU (LOG_BITMASK's IMU bit)",
                spelling: None,
            }
            .into());
        };
        let (rec, mut paired) = pair_streams(acc, gyro);
        warnings.append(&mut paired);
        Ok((rec, warnings))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn fmt_body(ty: u8, len: u8, name: &str, format: &str, cols: &str) -> Vec<u8> {
        let mut b = vec![ty, len];
        let pad = |s: &str, n: usize| {
            let mut v = s.as_bytes().to_vec();
            v.resize(n, 0);
            v
        };
        b.extend(pad(name, 4));
        b.extend(pad(format, 16));
        b.extend(pad(cols, 64));
        b
    }

    #[test]
    fn a_format_adds_up_to_its_length_or_is_refused() {
        let cols = "TimeUS,I,GyrX,GyrY,GyrZ,AccX,AccY,AccZ,EG,EA,T,GH,AH,GHz,AHz";
        let (t, f, _) = Format::parse(&fmt_body(40, 54, "IMU", "QBffffffIIfBBHH", cols)).unwrap();
        assert_eq!(t, 40);
        assert_eq!(f.column("AccX"), Some((3 + 8 + 1 + 12, b'f')));
        let l = layout(&f).unwrap();
        assert_eq!(l.kind, Kind::Imu);
        assert!(l.temperature.is_some());
        assert!(Format::parse(&fmt_body(40, 53, "IMU", "QBffffffIIfBBHH", cols)).is_none());
        assert!(Format::parse(&fmt_body(40, 54, "IMU", "QBffffffIIfBBH?", cols)).is_none());
    }

    #[test]
    fn numbers_are_scaled_like_pymavlink() {
        assert_eq!(number(&(-150i16).to_le_bytes(), 0, b'c'), Some(-1.5));
        assert_eq!(
            number(&(123_456_789i32).to_le_bytes(), 0, b'L'),
            Some(12.3456789)
        );
        assert_eq!(number(&[1, 2], 0, b'f'), None);
    }
}

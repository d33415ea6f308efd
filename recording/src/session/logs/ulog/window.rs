//! A window of a long ULog read from the survey's marks (`crate::session::logs::resume`): the
//! stretches of the file whose samples' times reach the window, each read with the definitions
//! and subscriptions the survey had there, and what is said of the whole file taken from the
//! survey.

use super::layout::{Field, Layout, Topic};
use super::{Keep, Recording, State, UlogError};
use crate::session::logs::resume::{stretches, Mark};
use crate::session::logs::StreamAt;
use crate::session::note::Note;
use std::collections::{BTreeSet, HashMap};
use std::fs::File;
use std::io::{BufReader, Seek, SeekFrom};
use std::sync::Arc;

/// The reader's state at a mark (`super::resume`): the definitions, the subscriptions, the data
/// appended later, and each stream's counts.
#[derive(Clone, Debug)]
pub(crate) struct At {
    pub(super) formats: Arc<HashMap<String, Vec<Field>>>,
    pub(super) subscribed: Arc<HashMap<u16, Layout>>,
    pub(super) appended: Vec<u64>,
    pub(super) fields: (usize, usize),
    pub(super) streams: [StreamAt; 4],
}

/// What a survey of a ULog leaves for the windows' passes (`super::resume`): its marks, and what
/// it found in the whole file.
#[derive(Debug)]
pub(crate) struct Resume {
    pub(super) marks: Vec<Mark<At>>,
    pub(super) streams: [StreamAt; 4],
    pub(super) seen: BTreeSet<(Topic, u8)>,
    pub(super) dropouts: Vec<(u64, f64, u16)>,
    pub(super) warnings: Vec<Note>,
}

/// One window of a long log (`keep`, a [`Keep::Span`]) read from the stretches of `file` its
/// samples lie in, as the survey's `resume` marks them (`super::resume`): the same samples and
/// words as [`super::read_keeping`] reading the whole file with `keep`.
pub(crate) fn read_window(
    file: &mut File,
    resume: &Resume,
    instance: u8,
    keep: &Keep,
    rate_hz: Option<f64>,
) -> Result<(Recording, Vec<Note>), UlogError> {
    let mut st = State::new(keep, rate_hz);
    let (lo, hi) = keep.reach();
    for (i, end) in stretches(&resume.marks, lo, hi) {
        let mark = &resume.marks[i];
        let mut offset = mark.offset;
        file.seek(SeekFrom::Start(offset))
            .map_err(|source| UlogError::Io { offset, source })?;
        let mut r = BufReader::with_capacity(1 << 20, &mut *file);
        st.formats = Arc::clone(&mark.state.formats);
        st.subscribed = Arc::clone(&mark.state.subscribed);
        st.appended.clone_from(&mark.state.appended);
        st.fields = mark.state.fields;
        for (s, at) in st.streams_mut().into_iter().zip(&mark.state.streams) {
            s.resume(at);
        }
        st.messages(&mut r, &mut offset, instance, end, None, &mut Vec::new())?;
    }
    for (s, at) in st.streams_mut().into_iter().zip(&resume.streams) {
        s.resume(at);
    }
    st.seen.clone_from(&resume.seen);
    st.dropouts.clone_from(&resume.dropouts);
    st.finish(instance, resume.warnings.clone())
}

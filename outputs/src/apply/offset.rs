//! The raw counts' zero force a calibration was made with, met by the one a raw log is read with.
//!
//! A session made from a logger's file holds the logger's own counts (the offset it was read with
//! added back, `session::from_recording::write_session`), so a calibration made from it has its
//! biases in those counts, the counts of zero force in them, and records that offset
//! (`calibration.toml`'s `raw_offset_lsb`). `apply` therefore compensates a raw log's own counts,
//! whatever offset it is read with: the offset only lets an unsigned output's mid-scale be read. One
//! given that is not the calibration's contradicts it and is refused with both figures; none given
//! reads the log with the calibration's.

use super::ApplyError;

/// How a raw log in counts is read for a calibration: the offset, and a note for the user.
#[derive(Clone, Debug, PartialEq)]
pub struct LogOffset {
    /// The counts of zero force to read the log with (added back before the compensation).
    pub read_with: [f64; 3],
    /// What was decided, when it is not what the user gave.
    pub note: Option<String>,
}

/// The offset to read a raw log with, from the one the calibration `name` records (`recorded`) and
/// the one given (`--acc-offset`, `given`).
pub fn log_offset(
    name: &str,
    recorded: Option<[f64; 3]>,
    given: Option<[f64; 3]>,
) -> Result<LogOffset, ApplyError> {
    if let Some(r) = recorded.filter(|r| r.iter().any(|x| !x.is_finite())) {
        return Err(ApplyError::RawOffset {
            calibration: name.to_string(),
            given: None,
            recorded: r,
        });
    }
    Ok(match (recorded, given) {
        (Some(r), Some(g)) if r == g => LogOffset {
            read_with: g,
            note: None,
        },
        (Some(r), Some(g)) => {
            return Err(ApplyError::RawOffset {
                calibration: name.to_string(),
                given: Some(g),
                recorded: r,
            })
        }
        (Some(r), None) => LogOffset {
            read_with: r,
            note: (r != [0.0; 3]).then(|| {
                format!(
                    "note: the log is read with the {} counts of zero force {name} was made with",
                    counts(r)
                )
            }),
        },
        (None, Some(g)) => LogOffset {
            read_with: g,
            note: Some(format!(
                "note: {name} does not record the counts of zero force it was made with (written \
                 before calibrations recorded them); it is applied to the log's own counts, as \
                 every session `host segment` writes holds them, and --acc-offset {} only reads \
                 the log",
                counts(g)
            )),
        },
        (None, None) => LogOffset {
            read_with: [0.0; 3],
            note: None,
        },
    })
}

/// An offset as the option takes it ([`UserOption::AccOffset`](recording::spelling::UserOption::AccOffset)): one number when the three are
/// equal, else X,Y,Z.
pub(crate) fn counts(v: [f64; 3]) -> String {
    if v[0] == v[1] && v[1] == v[2] {
        format!("{}", v[0])
    } else {
        format!("{},{},{}", v[0], v[1], v[2])
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The same offset reads the log once; another is refused with both figures; none reads the
    /// log with the calibration's; an older calibration takes the given one with a note.
    #[test]
    fn the_offsets_meet_or_are_refused_with_both_figures() {
        let mid = [32768.0; 3];
        let same = log_offset("cal.toml", Some(mid), Some(mid)).unwrap();
        assert_eq!((same.read_with, same.note), (mid, None));
        let e = log_offset("cal.toml", Some([80.0; 3]), Some(mid))
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("--acc-offset 32768") && e.contains("80 counts") && e.contains("cal.toml"),
            "{e}"
        );
        let from_cal = log_offset("cal.toml", Some(mid), None).unwrap();
        assert_eq!(from_cal.read_with, mid);
        assert!(from_cal.note.unwrap().contains("32768"));
        let old = log_offset("cal.toml", None, Some([1.0, 2.0, 3.0])).unwrap();
        assert_eq!(old.read_with, [1.0, 2.0, 3.0]);
        assert!(old.note.unwrap().contains("--acc-offset 1,2,3"));
        assert_eq!(
            log_offset("cal.toml", None, None).unwrap().read_with,
            [0.0; 3]
        );
        assert!(log_offset("cal.toml", Some([f64::NAN; 3]), None).is_err());
    }
}

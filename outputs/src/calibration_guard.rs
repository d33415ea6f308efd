//! One guard wherever a calibration meets something: a recording (`host apply`, `noise`, `report`,
//! `navigation-check`), a device (`flash`, the live procedure's `verify`, `read`) or another
//! calibration (`compare`, `batch`). [`verdict`] is the one table of which check applies at which
//! meeting (and, where one does not, why); `meet` runs the checks that apply, in the table's order,
//! before anything is computed or written; `check_rest_rate` is the one check that needs the data
//! (the gyro's rate at rest). Every refusal ([`GuardError`]) names both sides and the fix.
//!
//! The scale check itself (sign and size of every scale factor) is the estimator's
//! ([`check_scales`]), which `host export` uses as well.

pub use estimator::calibration_guard::{check_scales, ScaleError};
use shared::{Calibration, OutputUnit, UnitId};

/// Largest mean gyro rate of a still segment after the calibration's bias, °/s: a MEMS gyro's
/// turn-on bias repeatability is below 1 °/s; a wrong unit (°/s read as rad/s) is 57× its bias.
pub(crate) const MAX_REST_RATE_DEG_S: f64 = 5.0;

/// Where a calibration meets something.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Meeting {
    /// `host apply`: a recording (a session or a logger's file).
    Apply,
    /// `host noise --calibration`: a recording.
    Noise,
    /// `host report`: a session.
    Report,
    /// `host navigation-check --unit`: a session simulated from the unit file.
    NavigationCheck,
    /// `host flash`: a device.
    Flash,
    /// The live procedure's verification: the calibration just made, on its device.
    Verify,
    /// `host read`: the calibration a device holds, against the device.
    Read,
    /// `host compare`: another calibration.
    Compare,
    /// `host batch`: the other calibrations of a lot.
    Batch,
}

impl Meeting {
    /// Every meeting, in the table's order.
    pub const ALL: [Meeting; 9] = [
        Meeting::Apply,
        Meeting::Noise,
        Meeting::Report,
        Meeting::NavigationCheck,
        Meeting::Flash,
        Meeting::Verify,
        Meeting::Read,
        Meeting::Compare,
        Meeting::Batch,
    ];

    /// The subcommand (or step) where it happens.
    pub fn command(self) -> &'static str {
        match self {
            Meeting::Apply => "apply",
            Meeting::Noise => "noise",
            Meeting::Report => "report",
            Meeting::NavigationCheck => "navigation-check",
            Meeting::Flash => "flash",
            Meeting::Verify => "verify",
            Meeting::Read => "read",
            Meeting::Compare => "compare",
            Meeting::Batch => "batch",
        }
    }

    /// Whether an all-zero unit id (a calibration of a session recorded without one) binds: where
    /// the other side's id must be matched exactly (a device accepts only its own; a recording with
    /// an id refuses another's), it does; where two files are only compared, it binds nothing.
    fn zero_id_binds(self) -> bool {
        !matches!(self, Meeting::Report | Meeting::Compare)
    }
}

/// What is checked where a calibration meets something.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Check {
    /// The unit ids agree (an absent id binds nothing).
    UnitId,
    /// The output units agree.
    OutputUnit,
    /// Every scale factor positive ([`check_scales`]).
    Scales,
    /// The body frames agree: the table's (known attitudes) or a convention (x along
    /// accelerometer x, no attitude known).
    Frame,
    /// A temperature model has temperatures to use, and a temperature to assume is used.
    Temperature,
    /// The gyro rests where the accelerometer does (`MAX_REST_RATE_DEG_S`): else it is in another
    /// unit than declared.
    GyroUnit,
}

impl Check {
    /// Every check, in the order `meet` runs them.
    pub const ALL: [Check; 6] = [
        Check::Scales,
        Check::UnitId,
        Check::OutputUnit,
        Check::Frame,
        Check::Temperature,
        Check::GyroUnit,
    ];

    /// Its name in the table.
    pub fn name(self) -> &'static str {
        match self {
            Check::UnitId => "unit id",
            Check::OutputUnit => "output unit",
            Check::Scales => "scale sign and size",
            Check::Frame => "body frame",
            Check::Temperature => "temperature model vs data",
            Check::GyroUnit => "gyro unit vs the rests",
        }
    }
}

/// Whether a check applies at a meeting.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Verdict {
    /// It is run, and a mismatch refused.
    Checked,
    /// It does not apply; why.
    DoesNotApply(&'static str),
}

const SIMULATED: &str =
    "the session is simulated from this unit file, so it is of its unit, output \
                         unit and frame by construction";
const OWN_DEVICE: &str =
    "the calibration verified is the one just made from this device's own outputs";
const DEVICE_NO_FRAME: &str = "a device applies the calibration in whatever body frame it has; \
                               it knows no frame of its own";
const BATCH_OWN: &str = "every calibration of a lot is fitted there from its own session";

/// The one table: whether `check` applies at `meeting`, and why not where it does not.
pub fn verdict(meeting: Meeting, check: Check) -> Verdict {
    use Check as C;
    use Meeting as M;
    use Verdict::{Checked, DoesNotApply as No};
    match (meeting, check) {
        (M::Apply | M::Noise | M::Report | M::Flash | M::Read | M::Compare, _)
            if matches!(check, C::UnitId | C::OutputUnit | C::Scales) =>
        {
            Checked
        }
        (M::NavigationCheck, C::Scales) => Checked,
        (M::NavigationCheck, C::UnitId | C::OutputUnit | C::Frame | C::GyroUnit) => No(SIMULATED),
        (M::NavigationCheck, C::Temperature) => No(
            "the session is simulated at the plan's temperatures, which the unit's model is \
             evaluated at",
        ),
        (M::Apply, C::Frame) => No(
            "the still check judges the magnitude of f and the rest rate, which no rotation of \
             the body frame changes",
        ),
        (M::Noise, C::Frame) => No(
            "the still check judges the magnitude of f, which no rotation of the body frame \
             changes",
        ),
        (M::Report | M::Compare, C::Frame) => Checked,
        (M::Apply | M::Report, C::Temperature) => Checked,
        (M::Noise, C::Temperature) => No(
            "the Allan deviation is blind to the constant offset of a model held at its \
             reference temperature",
        ),
        (M::Apply, C::GyroUnit) => Checked,
        (M::Noise, C::GyroUnit) => No(
            "noise converts only the accelerometer with the calibration; the gyro's rates are \
             analysed as recorded",
        ),
        (M::Report, C::GyroUnit) => {
            No("the report shows the gyro's rates as recorded; apply judges them at rest")
        }
        (M::Flash | M::Read, C::Frame) => No(DEVICE_NO_FRAME),
        (M::Flash | M::Read, C::Temperature) => No("the device measures its own temperature"),
        (M::Flash | M::Read, C::GyroUnit) => No(
            "the device's gyro rate comes in the unit its firmware declares; the calibration's \
             gyro was fitted from those outputs",
        ),
        (M::Verify, C::Frame) => No(
            "verify judges a conventional-frame calibration after the best common rotation of \
             the positions at rest (device/verify.rs)",
        ),
        (M::Verify, _) => No(OWN_DEVICE),
        (M::Compare, C::Temperature | C::GyroUnit) => No("two calibrations meet no data"),
        (M::Batch, C::OutputUnit) => {
            No("a lot that mixes output units is screened within each output unit, and says so")
        }
        (M::Batch, C::UnitId) => No(
            "units of a lot have different ids by design; two that claim the same id are failed",
        ),
        (M::Batch, _) => No(BATCH_OWN),
        (M::Apply | M::Noise | M::Report | M::Flash | M::Read | M::Compare, _) => Checked,
    }
}

/// A body frame, as a calibration or a recording has it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Frame {
    /// The table's (or fixture's): the positions' attitudes are known.
    Table,
    /// A convention: body x along accelerometer x, body y in its x–y sensing plane.
    Convention,
}

impl std::fmt::Display for Frame {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Frame::Table => "the table's body frame (known attitudes)",
            Frame::Convention => {
                "a conventional body frame (x along accelerometer x, no attitude known)"
            }
        })
    }
}

impl Frame {
    /// A calibration's frame: a conventional one holds accelerometer x's angles at exactly 0°, 90°,
    /// 90° and accelerometer y's angle to body z at exactly 90° (the fit keeps them fixed, docs
    /// /model.md §7); a fitted table frame never gives those exact values.
    pub(crate) fn of_calibration(cal: &Calibration) -> Frame {
        let a = &cal.statics.installation_angles_deg;
        if a[0] == [0.0, 90.0, 90.0] && a[1][2] == 90.0 {
            Frame::Convention
        } else {
            Frame::Table
        }
    }

    /// A recording's frame: the table's when the segments on the fixture have known ups in at
    /// least two directions (as the fit's own choice of frame: parallel ups leave a rotation about
    /// them free), else a convention (every position free, as a hand-held session's).
    pub(crate) fn of_plan(plan: &recording::session::Plan) -> Frame {
        let ups: Vec<[f64; 3]> = plan
            .segments
            .iter()
            .filter(|s| !s.is_free())
            .map(|s| s.up_b)
            .collect();
        let spread = ups.iter().any(|a| {
            ups.iter()
                .any(|b| shared::linalg::norm(&shared::linalg::cross(a, b)) > 0.2)
        });
        if spread {
            Frame::Table
        } else {
            Frame::Convention
        }
    }
}

/// The temperatures a recording gives a temperature model.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Temperatures {
    /// None recorded, none to assume.
    None,
    /// Recorded (a `temp_c` column); `assumed`: a temperature also given to assume.
    Recorded {
        /// The temperature given to assume (it would be ignored).
        assumed: Option<f64>,
    },
    /// None recorded; this one assumed.
    Assumed(f64),
}

/// The calibration's side of a meeting.
#[derive(Clone, Copy, Debug)]
pub struct Mine<'a> {
    /// As the messages name it ("the calibration", "A (a.toml)").
    pub name: &'a str,
    /// The calibration.
    pub cal: &'a Calibration,
    /// Its unit id (`None`: it has none).
    pub unit_id: Option<UnitId>,
}

/// What the calibration meets, as far as the checks need it (`None`: the side has no such thing).
#[derive(Clone, Debug)]
pub struct Other<'a> {
    /// As the messages name it ("the recording", "the device", "B (b.toml)").
    pub name: &'a str,
    /// Its unit id, as it gives it.
    pub unit_id: Option<String>,
    /// Its output unit.
    pub output_unit: Option<OutputUnit>,
    /// Its body frame.
    pub frame: Option<Frame>,
    /// Its temperatures.
    pub temperatures: Temperatures,
}

/// Why a calibration cannot meet what it meets. Each names both sides and the fix.
#[derive(Debug, thiserror::Error)]
pub enum GuardError {
    /// A scale factor is zero or negative.
    #[error("{mine} cannot meet {other}")]
    Scale {
        /// The calibration's side.
        mine: String,
        /// The other side.
        other: String,
        /// The scale factor.
        #[source]
        source: ScaleError,
    },
    /// The unit ids differ.
    #[error("{mine} is of unit {mine_id} but {other} is of unit {other_id}: {fix}")]
    UnitId {
        /// The calibration's side.
        mine: String,
        /// Its id.
        mine_id: UnitId,
        /// The other side.
        other: String,
        /// Its id, as given.
        other_id: String,
        /// What to do.
        fix: &'static str,
    },
    /// The output units differ.
    #[error("{mine} maps outputs in {} but {other} is in {}: {fix}", .mine_unit.symbol(), .other_unit.symbol())]
    OutputUnit {
        /// The calibration's side.
        mine: String,
        /// Its output unit.
        mine_unit: OutputUnit,
        /// The other side.
        other: String,
        /// Its output unit.
        other_unit: OutputUnit,
        /// What to do.
        fix: &'static str,
    },
    /// The body frames differ.
    #[error("{mine} is in {mine_frame} but {other} is in {other_frame}: {fix}")]
    Frame {
        /// The calibration's side.
        mine: String,
        /// Its frame.
        mine_frame: Frame,
        /// The other side.
        other: String,
        /// Its frame.
        other_frame: Frame,
        /// What to do.
        fix: &'static str,
    },
    /// A temperature model, and no temperature to evaluate it at.
    #[error("{mine} has a temperature model but {other} has no temp_c column: {fix}")]
    NoTemperature {
        /// The calibration's side.
        mine: String,
        /// The other side.
        other: String,
        /// What to do.
        fix: &'static str,
    },
    /// A temperature to assume where the recording has its own (it would be ignored).
    #[error(
        "--temperature-c does not apply: {other} has its own temperatures (temp_c), which the \
         temperature model of {mine} uses; leave it out"
    )]
    TemperatureNotUsed {
        /// The calibration's side.
        mine: String,
        /// The other side.
        other: String,
    },
    /// A still segment's gyro rate after the calibration's bias is far from zero.
    #[error(
        "still segment '{segment}' of {other} has a gyro rate of {deg_s:.2} °/s after the bias of \
         {mine} (at most {MAX_REST_RATE_DEG_S} °/s is plausible): the gyro's unit or the \
         calibration's gyro does not fit this recording"
    )]
    RestRate {
        /// The calibration's side.
        mine: String,
        /// The other side.
        other: String,
        /// The segment.
        segment: String,
        /// Its mean rate, °/s.
        deg_s: f64,
    },
}

/// Runs every check the table ([`verdict`]) applies at `meeting` but the gyro's rest (which needs
/// the data: `check_rest_rate`), in the order of [`Check::ALL`].
pub fn meet(meeting: Meeting, mine: &Mine, other: &Other) -> Result<(), GuardError> {
    for check in Check::ALL {
        if verdict(meeting, check) != Verdict::Checked {
            continue;
        }
        match check {
            Check::Scales => check_scales(mine.cal).map_err(|source| GuardError::Scale {
                mine: mine.name.to_string(),
                other: other.name.to_string(),
                source,
            })?,
            Check::UnitId => check_unit_id(meeting, mine, other)?,
            Check::OutputUnit => check_output_unit(meeting, mine, other)?,
            Check::Frame => check_frame(meeting, mine, other)?,
            Check::Temperature => check_temperature(meeting, mine, other)?,
            Check::GyroUnit => {}
        }
    }
    Ok(())
}

fn check_unit_id(meeting: Meeting, mine: &Mine, other: &Other) -> Result<(), GuardError> {
    let binds = |id: UnitId| meeting.zero_id_binds() || id != UnitId::default();
    let (Some(m), Some(o)) = (mine.unit_id.filter(|i| binds(*i)), other.unit_id.as_deref()) else {
        return Ok(());
    };
    let parsed = UnitId::parse_hex(o);
    if parsed == Some(m) || parsed.is_some_and(|p| !binds(p)) {
        return Ok(());
    }
    Err(GuardError::UnitId {
        mine: mine.name.to_string(),
        mine_id: m,
        other: other.name.to_string(),
        other_id: o.to_string(),
        fix: match meeting {
            Meeting::Apply => {
                "use that unit's calibration (or --ignore-unit-id if the recording's id is wrong)"
            }
            Meeting::Flash => {
                "flash it to its own unit, or flash this unit's calibration to this device"
            }
            Meeting::Read => "the device holds another unit's calibration: flash its own",
            Meeting::Compare => "compare calibrations of one unit",
            _ => "use the calibration of this unit",
        },
    })
}

fn check_output_unit(meeting: Meeting, mine: &Mine, other: &Other) -> Result<(), GuardError> {
    match other.output_unit {
        Some(o) => check_output_units(
            meeting,
            mine.name,
            mine.cal.statics.output_unit,
            other.name,
            o,
        ),
        None => Ok(()),
    }
}

/// [`Check::OutputUnit`] where only the two output units are at hand (a logger's file read after
/// the calibration was turned into matrices).
pub(crate) fn check_output_units(
    meeting: Meeting,
    mine: &str,
    mine_unit: OutputUnit,
    other: &str,
    other_unit: OutputUnit,
) -> Result<(), GuardError> {
    if mine_unit == other_unit {
        return Ok(());
    }
    Err(GuardError::OutputUnit {
        mine: mine.to_string(),
        mine_unit,
        other: other.to_string(),
        other_unit,
        fix: match meeting {
            Meeting::Flash | Meeting::Read => "flash a calibration made from this device's outputs",
            Meeting::Compare => {
                "the biases and scale factors are not comparable: compare calibrations in one \
                 output unit"
            }
            _ => "use a calibration of this recording's unit and output unit",
        },
    })
}

fn check_frame(meeting: Meeting, mine: &Mine, other: &Other) -> Result<(), GuardError> {
    let mine_frame = Frame::of_calibration(mine.cal);
    let Some(other_frame) = other.frame else {
        return Ok(());
    };
    // A table-frame calibration fits a recording of free attitudes (each is estimated); only a
    // conventional one cannot be held against the table's known attitudes.
    let differ = match meeting {
        Meeting::Compare => mine_frame != other_frame,
        _ => mine_frame == Frame::Convention && other_frame == Frame::Table,
    };
    if !differ {
        return Ok(());
    }
    Err(GuardError::Frame {
        mine: mine.name.to_string(),
        mine_frame,
        other: other.name.to_string(),
        other_frame,
        fix: match meeting {
            Meeting::Compare => {
                "their installation angles differ by the frames' rotation, not by the unit: \
                 compare calibrations made the same way"
            }
            _ => {
                "its installation angles cannot be held against the table's attitudes: use a \
                 calibration made on the table"
            }
        },
    })
}

fn check_temperature(meeting: Meeting, mine: &Mine, other: &Other) -> Result<(), GuardError> {
    match other.temperatures {
        Temperatures::Recorded { assumed: Some(_) } => Err(GuardError::TemperatureNotUsed {
            mine: mine.name.to_string(),
            other: other.name.to_string(),
        }),
        Temperatures::None if mine.cal.temperature.is_some() => Err(GuardError::NoTemperature {
            mine: mine.name.to_string(),
            other: other.name.to_string(),
            fix: match meeting {
                Meeting::Apply => {
                    "say which temperature to assume with --temperature-c C (the model's error \
                     grows with the distance from the recording's real temperature)"
                }
                _ => {
                    "its segments cannot be compensated at their temperature; use a recording \
                     with temperatures"
                }
            },
        }),
        _ => Ok(()),
    }
}

/// The gyro's rest ([`Check::GyroUnit`]; `mine`, `other`: the two sides' names): a still segment's
/// mean rate after the calibration's bias, `deg_s`, must be below [`MAX_REST_RATE_DEG_S`] (NaN is refused).
pub(crate) fn check_rest_rate(
    mine: &str,
    other: &str,
    segment: &str,
    deg_s: f64,
) -> Result<(), GuardError> {
    if deg_s.is_nan() || deg_s > MAX_REST_RATE_DEG_S {
        return Err(GuardError::RestRate {
            mine: mine.to_string(),
            other: other.to_string(),
            segment: segment.to_string(),
            deg_s,
        });
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn other(output_unit: OutputUnit) -> Other<'static> {
        Other {
            name: "the recording",
            unit_id: None,
            output_unit: Some(output_unit),
            frame: Some(Frame::Table),
            temperatures: Temperatures::None,
        }
    }

    /// A table plan's frame is the table's; a hand-held plan's (all free) and one whose fixture
    /// ups are all parallel (z up and down: a rotation about z is left free) are conventions.
    #[test]
    fn a_plans_frame_needs_two_known_directions() {
        use recording::session::builtin::builtin_plan;
        let plan = |name| builtin_plan(name).unwrap().unwrap();
        assert_eq!(Frame::of_plan(&plan("short")), Frame::Table);
        assert_eq!(Frame::of_plan(&plan("hand")), Frame::Convention);
        let mut z_only = plan("short");
        z_only.segments.retain(|s| s.up_b[2].abs() > 0.99);
        assert!(!z_only.segments.is_empty());
        assert_eq!(Frame::of_plan(&z_only), Frame::Convention);
    }

    /// Every cell of the table is decided, and every "does not apply" says why.
    #[test]
    fn every_cell_is_checked_or_says_why_not() {
        for m in Meeting::ALL {
            for c in Check::ALL {
                if let Verdict::DoesNotApply(why) = verdict(m, c) {
                    assert!(why.len() > 20, "{m:?} × {c:?}: {why}");
                }
            }
        }
        assert_eq!(verdict(Meeting::Compare, Check::Frame), Verdict::Checked);
        assert_eq!(verdict(Meeting::Apply, Check::GyroUnit), Verdict::Checked);
    }

    /// The paper's unit (a table frame, volts) passes against a volts recording; each mismatch is
    /// refused naming both sides.
    #[test]
    fn each_mismatch_names_both_sides() {
        let cal = shared::params::PAPER_UNIT;
        let id = UnitId::parse_hex("a1b2c3d4e5f6a1b2c3d4e5f6");
        let mine = Mine {
            name: "the calibration",
            cal: &cal,
            unit_id: id,
        };
        assert!(meet(Meeting::Apply, &mine, &other(OutputUnit::Volts)).is_ok());
        let e = meet(
            Meeting::Apply,
            &mine,
            &other(OutputUnit::MetresPerSecondSquared),
        )
        .unwrap_err()
        .to_string();
        assert!(e.contains("in V but the recording is in m/s"), "{e}");
        let mut o = other(OutputUnit::Volts);
        o.unit_id = Some("0f0f0f0f0f0f0f0f0f0f0f0f".into());
        let e = meet(Meeting::Apply, &mine, &o).unwrap_err().to_string();
        assert!(
            e.contains("a1b2c3d4e5f6a1b2c3d4e5f6") && e.contains("0f0f0f0f"),
            "{e}"
        );
        let mut conv = cal;
        conv.statics.installation_angles_deg[0] = [0.0, 90.0, 90.0];
        conv.statics.installation_angles_deg[1][2] = 90.0;
        let mine_conv = Mine { cal: &conv, ..mine };
        let e = meet(Meeting::Report, &mine_conv, &other(OutputUnit::Volts)).unwrap_err();
        assert!(matches!(e, GuardError::Frame { .. }), "{e}");
        // The still check is blind to the frame: apply lets it through.
        assert!(meet(Meeting::Apply, &mine_conv, &other(OutputUnit::Volts)).is_ok());
        // What a device holds against the device (`host read`, which a simulated device cannot
        // drive: it starts empty): another unit's blob, another output unit, a negated scale.
        let device = Other {
            name: "the device",
            unit_id: Some("0f0f0f0f0f0f0f0f0f0f0f0f".into()),
            output_unit: Some(OutputUnit::Volts),
            frame: None,
            temperatures: Temperatures::None,
        };
        let e = meet(Meeting::Read, &mine, &device).unwrap_err().to_string();
        assert!(
            e.contains("a1b2c3d4e5f6a1b2c3d4e5f6") && e.contains("0f0f0f0f"),
            "{e}"
        );
        let device = Other {
            unit_id: None,
            output_unit: Some(OutputUnit::Lsb),
            ..device
        };
        let e = meet(Meeting::Read, &mine, &device).unwrap_err().to_string();
        assert!(e.contains("in V but the device is in LSB"), "{e}");
        let mut negated = cal;
        negated.statics.scale_out_per_g[1] *= -1.0;
        let e = meet(
            Meeting::Read,
            &Mine {
                cal: &negated,
                ..mine
            },
            &device,
        )
        .unwrap_err();
        assert!(matches!(e, GuardError::Scale { .. }), "{e}");
        assert!(check_rest_rate("the calibration", "the recording", "x+", 57.3).is_err());
        assert!(check_rest_rate("the calibration", "the recording", "x+", 0.5).is_ok());
    }
}

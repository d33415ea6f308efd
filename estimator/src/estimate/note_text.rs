//! The wording of the fit's warnings about the session and its result ([`Note`]'s variants from
//! [`Note::SegmentNotInPlan`] on): what each says to the user, with the figures the note carries.

use super::note::{MisfitSources, Note};
use recording::spelling::UserOption;
use std::fmt;

impl Note {
    /// The text of a warning about the session or the fit (the other notes are worded in
    /// `note.rs`).
    pub(super) fn fmt_warning(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Note::SegmentNotInPlan { segment } => write!(
                f,
                "segment '{segment}' is in the data but not in the plan: ignored (add it to \
                 plan.toml to use it)"
            ),
            Note::SegmentMissingFromData { segment } => write!(
                f,
                "segment '{segment}' is in the plan but has no rows in the data: left out (record \
                 it, or remove it from plan.toml)"
            ),
            // One lever arm: it is the package's distance from the table's axis (docs/model.md §4.7).
            Note::NoTableCentre {
                single_package: true,
            } => f.write_str(
                "the plan gives no table centre: the package's lever arm is relative to the point \
                 on the table's spin axis (p = 0), i.e. where the package sat on the table",
            ),
            Note::NoTableCentre {
                single_package: false,
            } => f.write_str(
                "the plan gives no table centre: the lever arms are relative to the point on the \
                 table's spin axis (the paper's assumption p = 0); only differences r_i − r_j are \
                 free of it",
            ),
            Note::TableCentreDiffers => f.write_str(
                "the table centre differs between segments (or is missing for some): the lever arms \
                 are relative to the plan's body origin",
            ),
            Note::NoResidualDof => f.write_str(
                "no residual degrees of freedom: the χ² check and scaling are not possible; add \
                 segments (repeat attitudes or rates)",
            ),
            Note::ChiSquareScaled {
                reduced,
                dof,
                sources,
                sigma_scale,
            } => write!(
                f,
                "χ²/dof = {reduced:.1} (dof {dof}): the residuals exceed the segments' own noise, so \
                 the model misses an error source it cannot see ({}); the 1σ values are scaled by \
                 {sigma_scale:.2}",
                sources.text()
            ),
            Note::LeverArmsUndetermined { .. } => self.fmt_lever_arms(f),
            Note::SegmentResidualsHigh { .. } => self.fmt_residuals(f),
            Note::GyroWalkUnused { why } => write!(
                f,
                "gyro: the unit's gyro bias random walk is left out: {why} (docs/model.md §11.6)"
            ),
            Note::MountsTilted { mounts } => {
                let bad: Vec<String> = mounts
                    .iter()
                    .map(|t| {
                        format!(
                            "{} {:.3}° ± {:.3}° (prior {:.3}°)",
                            t.name,
                            t.tilt_deg,
                            t.sigma_deg,
                            t.prior_deg.unwrap_or(0.0)
                        )
                    })
                    .collect();
                write!(
                    f,
                    "mount(s) tilted more than 3× the plan's attitude_sigma_deg: {}; the fixture is \
                     worse than the plan says, or the unit was mounted wrongly: check the fixture \
                     and set attitude_sigma_deg to its real accuracy (docs/model.md §7)",
                    bad.join(", ")
                )
            }
            Note::BodyFrame(frame) => write!(f, "{frame}"),
            _ => self.fmt_gyro_and_labels(f),
        }
    }

    /// The warnings about the gyro's sources, the static segments' labels and the lever arms'
    /// one package.
    fn fmt_gyro_and_labels(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Note::GyroFromRests {
                bias_rad_s: b,
                sigma_rad_s: s,
            } => write!(
                f,
                "gyro: bias at the reference temperature from the rests, ({:+.4}, {:+.4}, {:+.4}) \
                 ± ({:.4}, {:.4}, {:.4}) °/s; its scale factors and axis alignment (G) are not \
                 determined (the session has no spins) and are taken as perfect",
                b[0].to_degrees(),
                b[1].to_degrees(),
                b[2].to_degrees(),
                s[0].to_degrees(),
                s[1].to_degrees(),
                s[2].to_degrees()
            ),
            Note::GyroTurnsAndRests { bias_rad_s } => {
                let b = bias_rad_s.map(f64::to_degrees);
                write!(
                    f,
                    "gyro: scale factors and axis alignment (G) from the hand turns (gyro.toml); \
                     the bias at the reference temperature, ({:+.4}, {:+.4}, {:+.4}) °/s, and its \
                     change with temperature from the rests (docs/model.md §8, §9), not the hand \
                     turns' bias, which is the still positions' average over their temperatures",
                    b[0], b[1], b[2]
                )
            }
            Note::LabelNotRecorded {
                segment,
                up_b: m,
                angle_deg,
            } => write!(
                f,
                "segment '{segment}' measures up ≈ [{:+.2}, {:+.2}, {:+.2}], {angle_deg:.0}° from \
                 its up_b: it was not recorded in the planned attitude",
                m[0], m[1], m[2]
            ),
            Note::LabelLooksLike { segment, alike } => {
                let alike: Vec<String> = alike.iter().map(|a| format!("'{a}'")).collect();
                write!(
                    f,
                    "segment '{segment}' looks like {} (its data point where that label's up_b \
                     does): the labels are swapped, or the unit was mounted wrongly",
                    alike.join(" or ")
                )
            }
            Note::GyroCommonScale { k } => write!(
                f,
                "the gyro reads {k:.4}× the table's rates on all three axes: its nominal scale is \
                 off by {:+.1} %, which this calibration corrects, or the plan's rate_deg_s are off \
                 by as much",
                (k - 1.0) * 100.0
            ),
            Note::PackageUntested => f.write_str(
                "the session cannot test whether the three accelerometers share one lever arm \
                 (their separate lever arms are not all estimable from its rotations): the \
                 one-point model is taken as given",
            ),
            Note::LeverArmsAlike {
                delta_chi2,
                dof,
                limit,
                spelling,
            } => write!(
                f,
                "the three accelerometers' lever arms do not differ significantly (one point for \
                 the three raises χ² by only {delta_chi2:.1} for {dof} degrees of freedom, below \
                 its 95 % point {limit:.1}): the per-accelerometer values fit noise; if the \
                 accelerometers share one package (a MEMS IMU), calibrate with {} (or package = \
                 \"single\" in plan.toml) to fit the package's one lever arm with a smaller 1σ",
                spelling.switch(UserOption::SinglePackage)
            ),
            _ => Ok(()),
        }
    }

    /// [`Note::LeverArmsUndetermined`]'s text.
    fn fmt_lever_arms(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let Note::LeverArmsUndetermined {
            components,
            threshold_m,
            fixed_at_zero,
        } = self
        else {
            return Ok(());
        };
        write!(
            f,
            "the plan does not determine lever-arm component(s) {} to {:.0} µm",
            components.join(", "),
            threshold_m * 1e6
        )?;
        if !fixed_at_zero.is_empty() {
            write!(
                f,
                " ({} not observable at all: fixed at 0)",
                fixed_at_zero.join(", ")
            )?;
        }
        f.write_str(
            "; add rotations about oblique axes (tilted mounts) and/or spin-up segments \
             (docs/model.md §4.4)",
        )
    }

    /// [`Note::SegmentResidualsHigh`]'s text: the error sources the segments' kinds point to.
    fn fmt_residuals(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let Note::SegmentResidualsHigh {
            segments,
            free,
            statics,
            rotating,
        } = self
        else {
            return Ok(());
        };
        let mut sources = Vec::new();
        if *free {
            sources.push(
                "movement while held still or bias drift (the attitude is fitted, the bias taken \
                 as constant)",
            );
        }
        if *statics {
            sources.push(
                "a mount tilted beyond its attitude prior, or bias drift (the bias is taken as \
                 constant)",
            );
        }
        if *rotating {
            sources.push(
                "rate-dependent effects outside the model (table wobble, a table centre off the \
                 spin axis, gyro scale or misalignment)",
            );
        }
        write!(
            f,
            "segment(s) {} have residuals well above their own noise: {}",
            segments.join(", "),
            sources.join("; ")
        )
    }
}

impl MisfitSources {
    fn text(self) -> &'static str {
        match self {
            MisfitSources::HeldStill => {
                "movement while held still, bias drift, a temperature change"
            }
            MisfitSources::Fixture => {
                "a mount tilted beyond its attitude prior, bias drift, a temperature change"
            }
            MisfitSources::Table => {
                "table attitude or rate error, bias drift, a table centre off the spin axis"
            }
        }
    }
}

//! What a fit says about how it chose its model, beside its numbers: each a [`Note`] carrying its
//! figures, not its text, so that a caller can tell one from another (its [`Note::code`]) without
//! matching words; its `Display` is the one wording every caller prints. The wording of the
//! warnings about the session and the fit is in `note_text.rs`.

use std::fmt;

/// One thing a fit chose or used, with the figures its message states.
#[derive(Clone, Debug, PartialEq)]
pub enum Note {
    /// The temperature model's degrees of one accelerometer, chosen by least BIC.
    ThermalAccDegrees {
        /// The axis (0, 1, 2).
        axis: usize,
        /// The zero bias's degree.
        zero_bias_degree: usize,
        /// The scale's degree.
        scale_degree: usize,
        /// χ²/dof of the model chosen.
        chi2_per_dof: f64,
        /// Its 1σ scaled by √(χ²/dof) (χ²/dof above 1).
        scaled: bool,
    },
    /// The temperature model's degree of one gyro axis's bias, chosen by least BIC.
    ThermalGyroDegree {
        /// The axis (0, 1, 2).
        axis: usize,
        /// The bias's degree.
        degree: usize,
        /// The degrees compared.
        compared: usize,
        /// χ²/dof of the model chosen.
        chi2_per_dof: f64,
    },
    /// The paper's eq. 24: the rates used and the noise its division by cos θ amplifies.
    PaperEq24 {
        /// The nominal rates used, °/s.
        rates_dps: Vec<f64>,
        /// The smallest cos θ_ij divided by.
        worst_cos: f64,
    },
    /// A misalignment that changes with temperature, which the model keeps constant.
    MisalignmentDrift {
        /// The accelerometer (0, 1, 2).
        axis: usize,
        /// The axis it leans towards.
        towards: usize,
        /// The slope, µrad/°C.
        slope_urad_per_c: f64,
        /// Its 1σ, µrad/°C.
        sigma_urad_per_c: f64,
        /// χ² of a constant misalignment.
        chi2: f64,
        /// Its degrees of freedom.
        dof: f64,
        /// The soak temperatures compared.
        soaks: usize,
        /// The 99.9 % bound on χ².
        bound: f64,
    },
    /// No temperature model: the static segments span too few degrees.
    ThermalSpanShort {
        /// The lowest temperature, °C.
        lo: f64,
        /// The highest, °C.
        hi: f64,
    },
    /// No temperature model: no four known attitudes out of one plane are each seen over the span
    /// a model needs.
    ThermalNotDetermined {
        /// The lowest temperature, °C.
        lo: f64,
        /// The highest, °C.
        hi: f64,
        /// Known attitudes seen over the span a model needs.
        attitudes: usize,
        /// Static segments with a free attitude.
        free: usize,
        /// Static segments in all.
        total: usize,
        /// The widest span at one known attitude, °C, and its mount.
        widest: Option<(f64, String)>,
    },
    /// A simulated unit's installation angles normalised (its rows' norms not 1).
    SimNormalised {
        /// The rows' norms.
        row_norms: [f64; 3],
    },
    /// A simulated session's output unit changed to the unit's.
    SimOutputUnit {
        /// The plan's unit.
        plan: shared::OutputUnit,
        /// The unit's.
        unit: shared::OutputUnit,
    },
    /// A segment of the data the plan does not name: ignored.
    SegmentNotInPlan {
        /// The segment's name.
        segment: String,
    },
    /// A segment of the plan with no rows in the data: left out.
    SegmentMissingFromData {
        /// The segment's name.
        segment: String,
    },
    /// A session that turns without a table centre in its plan: the lever arms are relative to
    /// the spin axis (docs/model.md §4.5).
    NoTableCentre {
        /// One lever arm for the three accelerometers (§4.7).
        single_package: bool,
    },
    /// The table centre differs between segments or is missing for some: the lever arms are
    /// relative to the plan's body origin (docs/model.md §4.5).
    TableCentreDiffers,
    /// No residual degree of freedom: χ² cannot be checked or scaled by.
    NoResidualDof,
    /// χ²/dof well above 1: the 1σ values scaled by √(χ²/dof).
    ChiSquareScaled {
        /// χ²/dof.
        reduced: f64,
        /// Its degrees of freedom.
        dof: i64,
        /// What the session's kind points to.
        sources: MisfitSources,
        /// √(χ²/dof), the factor on every 1σ.
        sigma_scale: f64,
    },
    /// Lever-arm components the plan does not determine (docs/model.md §4.4).
    LeverArmsUndetermined {
        /// Their names.
        components: Vec<String>,
        /// The 1σ above which a component is undetermined, m.
        threshold_m: f64,
        /// Those not observable at all, fixed at 0.
        fixed_at_zero: Vec<String>,
    },
    /// Segments whose residuals are well above their own noise.
    SegmentResidualsHigh {
        /// Their names.
        segments: Vec<String>,
        /// Some have a free attitude.
        free: bool,
        /// Some are static at a known attitude.
        statics: bool,
        /// Some rotate.
        rotating: bool,
    },
    /// The unit's gyro bias random walk is left out of the fit (docs/model.md §11.6).
    GyroWalkUnused {
        /// Why the session has no gyro model to use it in.
        why: &'static str,
    },
    /// Mounts tilted more than 3× the plan's attitude prior (docs/model.md §7).
    MountsTilted {
        /// Each such mount.
        mounts: Vec<super::attitude::MountTilt>,
    },
    /// What fixes the body frame, when nothing known does (docs/model.md §7.1).
    BodyFrame(super::attitude::BodyFrame),
    /// The gyro's bias from the rests alone; `G` taken as perfect (docs/model.md §8, §9).
    GyroFromRests {
        /// The bias at the reference temperature, rad/s.
        bias_rad_s: [f64; 3],
        /// Its 1σ, rad/s.
        sigma_rad_s: [f64; 3],
    },
    /// The gyro's `G` from the hand turns, its bias from the rests (docs/model.md §8, §9).
    GyroTurnsAndRests {
        /// The bias at the reference temperature, rad/s.
        bias_rad_s: [f64; 3],
    },
    /// A static segment's data point nowhere near its label's up.
    LabelNotRecorded {
        /// The segment.
        segment: String,
        /// The measured up, normalised, body axes.
        up_b: [f64; 3],
        /// Its angle from the label's `up_b`, degrees.
        angle_deg: f64,
    },
    /// A static segment's data point where other labels' do.
    LabelLooksLike {
        /// The segment.
        segment: String,
        /// The labels it looks like.
        alike: Vec<String>,
    },
    /// A gyro reading `k`× the table's rates on all three axes: its nominal scale is off.
    GyroCommonScale {
        /// The common factor.
        k: f64,
    },
    /// One lever arm asked for, but the session cannot test it against three (docs/model.md
    /// §4.7).
    PackageUntested,
    /// Three lever arms that do not differ significantly: one package's would do (§4.7).
    LeverArmsAlike {
        /// χ² added by one point for the three.
        delta_chi2: f64,
        /// Its degrees of freedom.
        dof: i64,
        /// The 95 % point of χ² with `dof`.
        limit: f64,
        /// How the caller names its options.
        spelling: recording::spelling::Spelling,
    },
}

/// The error sources a χ²/dof well above 1 points to, by the session's kind.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MisfitSources {
    /// Every segment held still at a free attitude.
    HeldStill,
    /// Static at known attitudes.
    Fixture,
    /// The session turns on a table.
    Table,
}

impl Note {
    /// A stable name of the note's kind, for a program reading the notes (the JSON document,
    /// Python), independent of its wording.
    pub fn code(&self) -> &'static str {
        match self {
            Note::ThermalAccDegrees { .. } => "thermal_acc_degrees",
            Note::ThermalGyroDegree { .. } => "thermal_gyro_degree",
            Note::PaperEq24 { .. } => "paper_eq24",
            Note::MisalignmentDrift { .. } => "misalignment_drift",
            Note::ThermalSpanShort { .. } => "thermal_span_short",
            Note::ThermalNotDetermined { .. } => "thermal_not_determined",
            Note::SimNormalised { .. } => "sim_normalised",
            Note::SimOutputUnit { .. } => "sim_output_unit",
            Note::SegmentNotInPlan { .. } => "segment_not_in_plan",
            Note::SegmentMissingFromData { .. } => "segment_missing_from_data",
            Note::NoTableCentre { .. } => "no_table_centre",
            Note::TableCentreDiffers => "table_centre_differs",
            Note::NoResidualDof => "no_residual_dof",
            Note::ChiSquareScaled { .. } => "chi_square_scaled",
            Note::LeverArmsUndetermined { .. } => "lever_arms_undetermined",
            Note::SegmentResidualsHigh { .. } => "segment_residuals_high",
            Note::GyroWalkUnused { .. } => "gyro_walk_unused",
            Note::MountsTilted { .. } => "mounts_tilted",
            Note::BodyFrame(_) => "body_frame",
            Note::GyroFromRests { .. } => "gyro_from_rests",
            Note::GyroTurnsAndRests { .. } => "gyro_turns_and_rests",
            Note::LabelNotRecorded { .. } => "label_not_recorded",
            Note::LabelLooksLike { .. } => "label_looks_like",
            Note::GyroCommonScale { .. } => "gyro_common_scale",
            Note::PackageUntested => "package_untested",
            Note::LeverArmsAlike { .. } => "lever_arms_alike",
        }
    }

    /// The notes said as text, in order: what a caller that only prints them keeps.
    pub fn texts(notes: &[Note]) -> Vec<String> {
        notes.iter().map(ToString::to_string).collect()
    }
}

impl Note {
    /// [`Note::ThermalNotDetermined`]'s text: why, with the session's numbers.
    fn fmt_not_determined(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let Note::ThermalNotDetermined {
            lo,
            hi,
            attitudes,
            free,
            total,
            widest,
        } = self
        else {
            return Ok(());
        };
        let min_span = super::thermal::MIN_SPAN_C;
        write!(
            f,
            "no temperature model: the static segments span {lo:.1}..{hi:.1} °C, but "
        )?;
        if *attitudes == 0 {
            write!(f, "no known attitude is seen over {min_span} °C or more")?;
        } else {
            write!(
                f,
                "the {attitudes} known attitude(s) seen over {min_span} °C or more are not four \
                 attitudes out of one plane, which each axis's bias and scale need"
            )?;
        }
        write!(
            f,
            " ({free} of {total} static segments have a free attitude"
        )?;
        if let Some((span, name)) = widest {
            write!(
                f,
                "; the widest span at one known attitude is {span:.2} °C ({name})"
            )?;
        }
        write!(
            f,
            "); a temperature change seen only between different attitudes cannot be told from \
             the attitudes' own difference (docs/model.md §9), so the calibration is made without \
             a temperature model, its values the session's average over {lo:.1}..{hi:.1} °C; to \
             calibrate over temperature, repeat the positions at several temperatures (soak steps) \
             or hold them through a ramp"
        )
    }
}

impl fmt::Display for Note {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Note::ThermalAccDegrees {
                axis,
                zero_bias_degree,
                scale_degree,
                chi2_per_dof,
                scaled,
            } => write!(
                f,
                "accelerometer {}: zero bias degree {zero_bias_degree}, scale degree \
                 {scale_degree} (least BIC of 16 pairs; χ²/dof {chi2_per_dof:.2}{})",
                shared::params::axis_name(*axis),
                if *scaled {
                    ", 1σ scaled by √(χ²/dof)"
                } else {
                    ""
                }
            ),
            Note::ThermalGyroDegree {
                axis,
                degree,
                compared,
                chi2_per_dof,
            } => write!(
                f,
                "gyro {}: bias degree {degree} over temperature (least BIC of {compared} degrees; \
                 χ²/dof {chi2_per_dof:.2})",
                shared::params::axis_name(*axis)
            ),
            Note::PaperEq24 {
                rates_dps,
                worst_cos,
            } => write!(
                f,
                "paper eq. 24 at {rates_dps:?} °/s (nominal rates, p = 0): the across-axis \
                 components are divided by cos θ_ij as small as {worst_cos:.4}, amplifying their \
                 noise up to {:.0}×",
                1.0 / worst_cos
            ),
            Note::MisalignmentDrift {
                axis,
                towards,
                slope_urad_per_c,
                sigma_urad_per_c,
                chi2,
                dof,
                soaks,
                bound,
            } => write!(
                f,
                "the misalignment of accelerometer {} towards {} changes with temperature: \
                 {slope_urad_per_c:.1} ± {sigma_urad_per_c:.1} µrad/°C (χ² {chi2:.1} on {dof} dof \
                 across {soaks} soak temperatures, above the 99.9 % bound {bound:.1}); the model \
                 keeps it constant",
                shared::params::axis_name(*axis),
                shared::params::axis_name(*towards)
            ),
            Note::ThermalSpanShort { lo, hi } => write!(
                f,
                "the static segments span {lo:.1}..{hi:.1} °C, less than {} °C: no temperature \
                 model (record soak steps or a ramp to calibrate over temperature)",
                super::thermal::MIN_SPAN_C
            ),
            Note::ThermalNotDetermined { .. } => self.fmt_not_determined(f),
            Note::SimNormalised { row_norms } => write!(
                f,
                "the unit's installation angles are inconsistent (row norms {row_norms:.7?}); \
                 simulated with each sensing direction normalised (docs/model.md §4.2), as written \
                 to truth.toml"
            ),
            Note::SimOutputUnit { plan, unit } => write!(
                f,
                "the plan's output_unit {} was changed to the unit's, {}",
                plan.symbol(),
                unit.symbol()
            ),
            _ => self.fmt_warning(f),
        }
    }
}

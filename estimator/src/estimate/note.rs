//! What a fit says about how it chose its model, beside its numbers: each a [`Note`] carrying its
//! figures, not its text, so that a caller can tell one from another (its [`Note::code`]) without
//! matching words; its `Display` is the one wording every caller prints.

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
        }
    }
}

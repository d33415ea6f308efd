//! Why the estimator made no calibration.

use shared::params::ParamsError;

/// Why no calibration could be made.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum EstimateError {
    /// No usable static segment.
    #[error(fmt = no_static_segments)]
    NoStaticSegments {
        /// How many static segments the plan has (all excluded when > 0).
        planned: usize,
        /// Why each was excluded ("'x+': …").
        reasons: Vec<String>,
    },
    /// The usable static attitudes do not span 3-D (the bias and `M` need ≥ 4 attitudes not on a plane).
    #[error(fmt = too_few_attitudes)]
    TooFewAttitudes {
        /// Usable static attitudes.
        attitudes: usize,
        /// Directions along which an attitude is missing (unit vectors, body axes).
        needed_directions: Vec<[f64; 3]>,
        /// Every segment left out, with its reason, figure and limit.
        dropped: Vec<String>,
    },
    /// Too few static positions are left for a fit with free attitudes (a hand-held or six-face
    /// session, docs/model.md §7).
    #[error(
        "{left} static position(s) left of the {planned} planned; a fit without known attitudes \
         needs {needed}: re-record the positions left out, or record more. Left out ({}):\n  - {}",
        .dropped.len(),
        .dropped.join("\n  - ")
    )]
    TooFewPositions {
        /// Distinct static positions left after screening.
        left: usize,
        /// Positions the fit needs.
        needed: usize,
        /// Static segments in the plan.
        planned: usize,
        /// Every segment left out, with its reason, figure and limit.
        dropped: Vec<String>,
    },
    /// The plan cannot determine these parameters.
    #[error("the plan cannot determine {}: {hint}", .parameters.join(", "))]
    PlanCannotObserve {
        /// The parameters.
        parameters: Vec<String>,
        /// What to add to the plan.
        hint: String,
    },
    /// The normal equations are singular.
    #[error("the {what} is singular: the segments do not determine the parameters")]
    Singular {
        /// Which fit.
        what: &'static str,
    },
    /// A plan segment has no data (strict mode).
    #[error(
        "segment '{name}' is in the plan but has no rows in the data: record it or remove it from plan.toml"
    )]
    MissingSegment {
        /// Its name.
        name: String,
    },
    /// The data have a segment the plan does not list (strict mode).
    #[error(
        "segment '{name}' is in the data but not in the plan: add it to plan.toml (up_b, rate_deg_s) or drop its rows"
    )]
    UnknownSegment {
        /// Its name.
        name: String,
    },
    /// The estimate is not a valid calibration.
    #[error("the estimate is not a valid calibration")]
    Params(#[from] ParamsError),
    /// The fit ran but its result is not a plausible unit (see [`super::plausibility`]).
    #[error(
        "no calibration written: the result is not plausible:\n  - {}",
        .problems.join("\n  - ")
    )]
    Implausible {
        /// Each problem, naming the segments or axes.
        problems: Vec<String>,
    },
    /// The single-package lever-arm model was asked for where it cannot apply (docs/model.md §4.7).
    #[error("the single-package lever-arm model: {0}")]
    SinglePackage(super::package::PackageRefusal),
    /// A bias random walk was asked of the paper's method, which has no weights to give it
    /// (docs/model.md §11).
    #[error(
        "a bias random walk weighs the joint fit's segments (docs/model.md §11); the paper's \
         eq. 24 is the published method: use the joint method, or leave the walk out"
    )]
    BiasWalkWithPaperMethod,
    /// A gyro bias random walk for a session without a gyro model: it would weigh nothing.
    #[error(
        "the gyro bias random walk does not apply: {why}, and the walk weighs only a gyro model's \
         mean rates (docs/model.md §11.6); leave it out"
    )]
    GyroBiasWalkUnused {
        /// Why the session has no gyro model.
        why: &'static str,
    },
    /// A walk from the unit's noise figures in the raw outputs of another unit than the
    /// session's: its strength would be read in the wrong unit.
    #[error(
        "the bias random walk from the unit's noise figures is in {walk}/√s (the noise analysis \
         was of outputs in {walk}), but this session's outputs are in {session}: give the noise \
         analysis of a recording in {session}, or one made with a calibration (in m/s²)"
    )]
    BiasWalkUnit {
        /// The walk's output unit.
        walk: &'static str,
        /// The session's output unit.
        session: &'static str,
    },
    /// The temperature model cannot be fitted or is implausible.
    #[error("temperature model: {0}; check the recording's temp_c column and the soak steps")]
    Temperature(super::thermal::ThermalError),
}

/// [`EstimateError::NoStaticSegments`]'s message: none planned, or all excluded and why.
fn no_static_segments(
    planned: &usize,
    reasons: &[String],
    f: &mut std::fmt::Formatter<'_>,
) -> std::fmt::Result {
    if *planned == 0 {
        write!(
            f,
            "the plan has no static segment: add at least four static attitudes (e.g. ±1 g on each axis)"
        )
    } else {
        write!(
            f,
            "0 static segments left of the {planned} planned, and at least four attitudes that span \
             3-D are needed: re-record them. Left out ({}):\n  - {}",
            reasons.len(),
            reasons.join("\n  - ")
        )
    }
}

/// [`EstimateError::TooFewAttitudes`]'s message, with each missing direction.
fn too_few_attitudes(
    attitudes: &usize,
    needed_directions: &[[f64; 3]],
    dropped: &[String],
    f: &mut std::fmt::Formatter<'_>,
) -> std::fmt::Result {
    write!(
        f,
        "the {attitudes} usable static attitude(s) do not span 3-D (at least four that do are \
         needed), so the biases and the scale/misalignment matrix are not determined; add static \
         segments with up_b along"
    )?;
    for d in needed_directions {
        write!(f, " ±[{:.3}, {:.3}, {:.3}]", d[0], d[1], d[2])?;
    }
    if !dropped.is_empty() {
        write!(
            f,
            ", or re-record those left out ({}):\n  - {}",
            dropped.len(),
            dropped.join("\n  - ")
        )?;
    }
    Ok(())
}

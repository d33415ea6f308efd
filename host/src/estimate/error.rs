//! Why the estimator made no calibration.

use shared::params::ParamsError;

/// Why no calibration could be made.
#[derive(Clone, Debug, PartialEq)]
pub enum EstimateError {
    /// No usable static segment.
    NoStaticSegments {
        /// How many static segments the plan has (all excluded when > 0).
        planned: usize,
        /// Why each was excluded ("'x+': …").
        reasons: Vec<String>,
    },
    /// The usable static attitudes do not span 3-D (the bias and `M` need ≥ 4 attitudes not on a plane).
    TooFewAttitudes {
        /// Usable static attitudes.
        attitudes: usize,
        /// Directions along which an attitude is missing (unit vectors, body axes).
        needed_directions: Vec<[f64; 3]>,
    },
    /// The plan cannot determine these parameters.
    PlanCannotObserve {
        /// The parameters.
        parameters: Vec<String>,
        /// What to add to the plan.
        hint: String,
    },
    /// The normal equations are singular.
    Singular {
        /// Which fit.
        what: &'static str,
    },
    /// A plan segment has no data (strict mode).
    MissingSegment {
        /// Its name.
        name: String,
    },
    /// The data have a segment the plan does not list (strict mode).
    UnknownSegment {
        /// Its name.
        name: String,
    },
    /// The estimate is not a valid calibration.
    Params(ParamsError),
    /// The fit ran but its result is not a plausible unit (see [`super::plausibility`]).
    Implausible {
        /// Each problem, naming the segments or axes.
        problems: Vec<String>,
    },
    /// The temperature model cannot be fitted or is implausible (the message says why).
    Temperature(String),
}

impl std::fmt::Display for EstimateError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            EstimateError::Temperature(why) => write!(
                f,
                "temperature model: {why}; check the recording's temp_c column and the soak steps"
            ),
            EstimateError::NoStaticSegments { planned: 0, .. } => write!(
                f,
                "the plan has no static segment: add at least four static attitudes (e.g. ±1 g on each axis)"
            ),
            EstimateError::NoStaticSegments { planned, reasons } => write!(
                f,
                "all {planned} static segments were excluded; re-record them. Reasons:\n  - {}",
                reasons.join("\n  - ")
            ),
            EstimateError::TooFewAttitudes {
                attitudes,
                needed_directions,
            } => {
                write!(
                    f,
                    "the {attitudes} usable static attitude(s) do not span 3-D, so the biases and the \
                     scale/misalignment matrix are not determined; add static segments with up_b along"
                )?;
                for d in needed_directions {
                    write!(f, " ±[{:.3}, {:.3}, {:.3}]", d[0], d[1], d[2])?;
                }
                Ok(())
            }
            EstimateError::PlanCannotObserve { parameters, hint } => write!(
                f,
                "the plan cannot determine {}: {hint}",
                parameters.join(", ")
            ),
            EstimateError::Singular { what } => write!(
                f,
                "the {what} is singular: the segments do not determine the parameters"
            ),
            EstimateError::MissingSegment { name } => write!(
                f,
                "segment '{name}' is in the plan but has no rows in the data: record it or remove it from plan.toml"
            ),
            EstimateError::UnknownSegment { name } => write!(
                f,
                "segment '{name}' is in the data but not in the plan: add it to plan.toml (up_b, rate_deg_s) or drop its rows"
            ),
            EstimateError::Params(e) => write!(f, "the estimate is not a valid calibration: {e}"),
            EstimateError::Implausible { problems } => write!(
                f,
                "no calibration written: the result is not plausible:\n  - {}",
                problems.join("\n  - ")
            ),
        }
    }
}

impl std::error::Error for EstimateError {}

impl From<ParamsError> for EstimateError {
    fn from(e: ParamsError) -> Self {
        EstimateError::Params(e)
    }
}

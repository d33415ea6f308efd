//! What each segment of a plan is (static, constant rate, ramp) and the per-sample noise pooled over
//! the static ones: the one place both are decided, for the estimator and for the report.

use recording::session::{SegmentPlan, SegmentStats};
use shared::linalg::RowMajor3;

/// What a segment does.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SegmentKind {
    /// At rest.
    Static,
    /// Constant table rate.
    ConstantRate,
    /// Spin-up or spin-down.
    Ramp,
}

impl SegmentKind {
    /// The kind the plan gives a segment: no rate is static; a rate that changes over the segment
    /// (`rate_end_deg_s` different from `rate_deg_s`) is a ramp.
    pub fn of(sp: &SegmentPlan) -> SegmentKind {
        if sp.is_static() {
            SegmentKind::Static
        } else if sp.rate_end_deg_s.is_some_and(|e| e != sp.rate_deg_s) {
            SegmentKind::Ramp
        } else {
            SegmentKind::ConstantRate
        }
    }
}

/// Per-sample noise, the mean of the covariances of static segments (at rest the outputs' and the
/// gyro's spread is noise alone; on a rotating segment it also holds the signal).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Noise {
    /// Mean output covariance, output unit².
    pub out_cov: RowMajor3,
    /// Mean gyro covariance, (rad/s)².
    pub gyro_cov: RowMajor3,
}

impl Noise {
    /// The mean covariances over `statics` (zero when there is none).
    pub fn pooled<'a>(statics: impl Iterator<Item = &'a SegmentStats>) -> Noise {
        let statics: Vec<&SegmentStats> = statics.collect();
        let n = statics.len().max(1) as f64;
        let mean = |f: &dyn Fn(&SegmentStats) -> RowMajor3| -> RowMajor3 {
            core::array::from_fn(|i| {
                core::array::from_fn(|j| statics.iter().map(|s| f(s)[i][j]).sum::<f64>() / n)
            })
        };
        Noise {
            out_cov: mean(&|s| s.cov_u),
            gyro_cov: mean(&|s| s.cov_w),
        }
    }
}

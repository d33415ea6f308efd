//! The 1σ of every estimated value in the paper's layout: what the estimator reports, what
//! `calibration.toml` stores as its `[uncertainty]` table and what the report and `host compare` read.

use serde::{Deserialize, Serialize};
use shared::linalg::RowMajor3;

/// `[uncertainty]`: 1σ of each estimated value.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Uncertainty {
    /// Zero-bias outputs, output unit.
    pub zero_bias_1sigma: [f64; 3],
    /// Scale factors, output unit per g.
    pub scale_per_g_1sigma: [f64; 3],
    /// Installation angles, degrees.
    pub installation_angles_deg_1sigma: RowMajor3,
    /// Lever arms, m.
    pub lever_arms_m_1sigma: RowMajor3,
    /// Which lever-arm components the plan determined (false: the value is not a measurement).
    pub lever_arms_observable: [[bool; 3]; 3],
}

//! The estimator's settings: which method, which reference point, when to scale by χ², how the gyro
//! is treated, and the screening thresholds.

use recording::spelling::Spelling;

/// Which estimator gives the result.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Method {
    /// Joint weighted least squares of all parameters from all segments (the default).
    Joint,
    /// Static least squares, then the lever arms by the paper's eq. 24 (for comparison).
    Paper,
}

impl std::fmt::Display for Method {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Method::Joint => "joint least squares",
            Method::Paper => "paper eq. 24",
        })
    }
}

/// Where the reported lever arms are measured from (`docs/model.md` §4.5).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ReferenceChoice {
    /// The point on the table's spin axis (the paper's p = 0), or the plan's body origin when the
    /// plan gives the table centre.
    TableAxis,
    /// The centroid of the three sensing points (free of the table centre).
    Centroid,
    /// A given point, body axes, metres, relative to the frame the fit uses (the table-axis point,
    /// or the plan's body origin when the plan gives the table centre).
    BodyPoint([f64; 3]),
}

/// When to scale the covariance by the reduced χ².
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ChiSquareScaling {
    /// Never: the weights (each segment's own noise) are taken as exact.
    Never,
    /// Always by χ²/dof (also below 1).
    Always,
    /// Only when χ²/dof exceeds its 99 % point for the degrees of freedom (a model error is visible).
    WhenSignificant,
}

/// Estimator settings.
#[derive(Clone, Debug, PartialEq)]
pub struct EstimateOptions {
    /// The method whose result goes into the calibration.
    pub method: Method,
    /// Also run the other method, for the comparison in the report (when the plan allows it).
    pub compare_methods: bool,
    /// Reference point of the reported lever arms.
    pub reference: ReferenceChoice,
    /// Use the measured ω̇ (the slope of ω over each segment); `false` turns the term off (`docs/model.md` §4.6).
    pub use_omega_dot: bool,
    /// χ² scaling of the covariance.
    pub chi2_scaling: ChiSquareScaling,
    /// A lever-arm component whose 1σ exceeds this is reported as not determined, m.
    pub lever_arm_threshold_m: f64,
    /// A lever-arm component whose 1σ exceeds this (with a weak 1 m prior) is not estimable at all and is
    /// fixed at 0, m.
    pub lever_arm_structural_limit_m: f64,
    /// The outputs' valid range (rails), output unit: a segment reaching it is saturated.
    pub output_range: Option<[f64; 2]>,
    /// A segment whose measured attitude is further than this from the plan's is excluded, degrees.
    pub attitude_tolerance_deg: f64,
    /// A static segment whose mean gyro rate differs from the other static segments' by more than this
    /// is moving, rad/s.
    pub motion_rate_threshold_rad_s: f64,
    /// A static segment whose output (or gyro) standard deviation is this many times the static median
    /// is moving.
    pub motion_noise_ratio: f64,
    /// Segments in the plan but not in the data (or the reverse) are errors instead of warnings.
    pub strict_segments: bool,
    /// Fail with [`super::EstimateError::PlanCannotObserve`] when any lever-arm component is not determined.
    pub require_lever_arms: bool,
    /// Use the gyro's mean axis during a spin as a measurement of the mount's true up, with this
    /// floor on its 1σ (how well the gyro's axes are taken to agree with the body frame), rad;
    /// `None`: do not (docs/model.md §7).
    pub gyro_axis_sigma_rad: Option<f64>,
    /// The gyro: estimated with the accelerometers (`w = G ω + b`, docs/model.md §8) or taken as
    /// perfect.
    pub gyro_model: GyroModel,
    /// The static parameters from the rest segments alone: a spin whose mount has a rest segment
    /// enters as its difference from it (docs/model.md §7), so a misfit of the dynamic model (a gyro
    /// error, an unmodelled ω̇) cannot move them. Off by default: with the mounts' tilts shared by
    /// their rest and spin segments and the gyro modelled, the joint fit already keeps a 1 mg misfit
    /// to a third of a 1σ move (tested), and it is twice as precise on the lever arms.
    pub static_from_rest: bool,
    /// The three accelerometers share one package (a MEMS IMU): one lever arm `r`, the package's
    /// position, for all three, and the in-package differences `r_i − r` reported as not observable
    /// (docs/model.md §4.7).
    pub single_package: bool,
    /// The accelerometers' bias random walk (docs/model.md §11).
    pub bias_walk: BiasWalk,
    /// The gyro's bias random walk, °/s/√s (docs/model.md §11.6): the gyro model's mean rates are
    /// weighted with its covariance across the session. 0 is a constant gyro bias, the default.
    pub gyro_bias_walk_deg_s_sqrt_s: f64,
    /// The gyro's bias random walk per axis (x, y, z), °/s/√s, in place of the one strength on
    /// every axis: the fit weighing the per-axis estimate where the session determines it
    /// (docs/model.md §11.6). Taken only with a `gyro_bias_walk_deg_s_sqrt_s` above 0 (the
    /// strongest of these); `None`, the default, is that one strength on the three axes.
    pub gyro_bias_walk_axes_deg_s_sqrt_s: Option<[f64; 3]>,
    /// The gyro's walk comes with the unit's noise figures (a file giving the accelerometers'
    /// walk too), not asked for: on a session without a gyro model it is left out with a warning
    /// instead of refused ([`super::EstimateError::GyroBiasWalkUnused`]).
    pub gyro_bias_walk_from_unit: bool,
    /// Estimate the gyro's bias random walk from the session when none is given (a
    /// `gyro_bias_walk_deg_s_sqrt_s` of 0), and weigh the gyro's means with it where the session
    /// determines it (docs/model.md §11.6); off, a constant gyro bias. The tools ask for it by
    /// default, with [`BiasWalk::Estimate`]; the library's default is the constant-bias fit.
    pub gyro_bias_walk_estimate: bool,
    /// How the caller names these options in refusals and warnings.
    pub spelling: Spelling,
}

impl EstimateOptions {
    /// These options as the tools fit by default: drift-aware, both bias walks estimated from the
    /// session and used where it determines them (docs/model.md §11.3, §11.6); the paper's
    /// method, which weighs no walk, keeps constant biases.
    pub fn drift_aware(self) -> EstimateOptions {
        let joint = self.method == Method::Joint;
        EstimateOptions {
            bias_walk: if joint {
                BiasWalk::Estimate
            } else {
                self.bias_walk
            },
            gyro_bias_walk_estimate: joint,
            ..self
        }
    }

    /// These options with the bias walk `walk`.
    pub fn with_bias_walk(&self, walk: BiasWalk) -> EstimateOptions {
        EstimateOptions {
            bias_walk: walk,
            ..self.clone()
        }
    }
}

/// How the estimator treats the accelerometers' bias over the session (docs/model.md §11).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum BiasWalk {
    /// A constant bias: every segment weighted by its own noise alone.
    Off,
    /// A random walk of this strength, mg/√s (0 is [`BiasWalk::Off`]).
    Given(f64),
    /// A random walk per axis taken from the unit's noise figures (a unit file's `[noise]`, or the
    /// Allan K of `host noise`), reported as taken from the unit (docs/model.md §11.3).
    FromUnit(UnitWalk),
    /// A random walk whose strength is estimated from the session (restricted maximum likelihood on
    /// the constant-bias fit's problem, §11.3), reported with its 1σ, and used where the session
    /// determines it ([`super::drift::Z_WALK`]); a session that determines none is the
    /// constant-bias fit, to the last digit.
    Estimate,
}

/// A per-axis walk strength from the unit's noise figures, in the unit it was measured in.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum UnitWalk {
    /// mg/√s per axis (a unit file's `accel_bias_walk_mg_sqrt_s`, or an Allan K in m/s²/√s or
    /// g/√s turned into mg): turned into output units with each axis's fitted scale factor.
    MgSqrtS([f64; 3]),
    /// Output unit/√s per axis (an Allan K of the raw outputs, V/√s or LSB/√s) and that output
    /// unit: the walk's intensity as it is, `q_i = K_i` (docs/model.md §11), for a session in
    /// the same unit only (another is refused, [`super::EstimateError::BiasWalkUnit`]).
    OutputPerSqrtS([f64; 3], shared::OutputUnit),
}

/// How the estimator treats the gyro.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum GyroModel {
    /// Its readings are the body's rate (then its spin axis measures each spinning mount's up).
    Perfect,
    /// `w = G ω + b` estimated from the same session when it has spins.
    Estimate,
}

/// The default of [`EstimateOptions::lever_arm_threshold_m`]: a lever-arm component below it,
/// m, is not determined (the full table's rule, which the summary uses too).
pub const LEVER_ARM_THRESHOLD_M: f64 = 2e-4;

impl EstimateOptions {
    /// The library's defaults (the constant-bias joint fit; the tools add
    /// [`EstimateOptions::drift_aware`]), the messages spelled as the caller spells its options.
    pub fn new(spelling: Spelling) -> EstimateOptions {
        EstimateOptions {
            method: Method::Joint,
            compare_methods: true,
            reference: ReferenceChoice::TableAxis,
            use_omega_dot: true,
            chi2_scaling: ChiSquareScaling::WhenSignificant,
            lever_arm_threshold_m: LEVER_ARM_THRESHOLD_M,
            lever_arm_structural_limit_m: 0.05,
            output_range: None,
            attitude_tolerance_deg: 3.0,
            motion_rate_threshold_rad_s: 0.5f64.to_radians(),
            motion_noise_ratio: 2.0,
            strict_segments: false,
            require_lever_arms: false,
            // 1 µrad: the gyro is taken as perfect (its axes are the body frame's), so the spin
            // axis's own noise weighs it (0.05 °/s over 60 s at 200 °/s is about 1 µrad). A gyro whose
            // axes are not calibrated should set its misalignment here, or `None`.
            gyro_axis_sigma_rad: Some(1e-6),
            gyro_model: GyroModel::Estimate,
            static_from_rest: false,
            single_package: false,
            bias_walk: BiasWalk::Off,
            gyro_bias_walk_deg_s_sqrt_s: 0.0,
            gyro_bias_walk_axes_deg_s_sqrt_s: None,
            gyro_bias_walk_from_unit: false,
            gyro_bias_walk_estimate: false,
            spelling,
        }
    }
}

/// Only for tests (feature `testkit`): [`EstimateOptions::new`] with the neutral test spelling. A
/// caller spells its own options.
#[cfg(any(test, feature = "testkit"))]
impl Default for EstimateOptions {
    fn default() -> Self {
        EstimateOptions::new(Spelling::default())
    }
}

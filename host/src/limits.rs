//! The bounds of the command line's numbers and of the device link; the recording's own are
//! [`recording::limits`]'s.

/// Shortest replayed navigation run (`--duration-s`), s: one step of the replay.
pub(crate) const MIN_NAVIGATION_DURATION_S: f64 = 0.01;

/// Longest replayed navigation run (`--duration-s`), s: one hour.
pub(crate) const MAX_NAVIGATION_DURATION_S: f64 = 3600.0;

/// Shortest wait for one answer of a device, s (below a millisecond no link answers).
pub(crate) const MIN_TIMEOUT_S: f64 = 1e-3;

/// Longest wait for one answer of a device, s.
pub(crate) const MAX_TIMEOUT_S: f64 = 3600.0;

/// Strongest accelerometer bias random walk `--bias-walk` takes, mg/√s: 1 mg/√s wanders a whole
/// milli-g every second, far beyond any accelerometer worth calibrating.
pub(crate) const MAX_BIAS_WALK_MG_SQRT_S: f64 = 1.0;

/// Strongest gyro bias random walk `--gyro-bias-walk` takes, °/s/√s: a bias that wanders a whole
/// °/s every second is no gyro worth calibrating (a plain MEMS gyro's is 10⁻⁴–10⁻³).
pub(crate) const MAX_GYRO_BIAS_WALK_DEG_S_SQRT_S: f64 = 1.0;

/// Most samples in one streamed window.
pub(crate) const MAX_WINDOW: u32 = 1_000_000;

/// Largest verification tolerance, mg (a tolerance above 1 g checks nothing).
pub(crate) const MAX_TOLERANCE_MG: f64 = 1000.0;

/// Fastest serial link, baud (USB bridges reach 12 Mbaud).
pub(crate) const MAX_BAUD: u32 = 12_000_000;

/// Slowest serial link, baud.
pub(crate) const MIN_BAUD: u32 = 300;

/// Largest simulated noise, drift or flicker level in mg or °/s: 10 g or 10 000 °/s of noise is no
/// sensor any more.
pub(crate) const MAX_SIM_NOISE: f64 = 1e4;

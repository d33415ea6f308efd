//! How a board mounts its IMU, and the rotation of each sample from the part's axes into the
//! board's: the calibration's body frame on a board with a digital IMU is the **board's** frame.
//!
//! Why the board's: the plan tells the operator "x-axis up", and the only axes on a flight
//! controller a person can see are the board's (its arrow forward, its top up), not the IMU's,
//! which the board may mount turned. Rotating in the firmware makes every stream, the calibration
//! and its installation angles (docs/model.md §4) refer to the axes printed on the board.
//!
//! The rotations are Betaflight's sensor alignments, named as its board definitions name them
//! (`GYRO_1_ALIGN`), with the mapping of its `alignSensorViaRotation`
//! (`src/main/sensors/boardalignment.c`): board = R · imu, for `CW90_DEG` board x = imu y,
//! board y = −imu x, board z = imu z. Each is a signed permutation: exact in `f32` (moves and sign
//! flips, no arithmetic), NaN stays NaN, no division or trigonometry per sample.

use super::ImuSample;

/// A right-angle rotation about the board's z axis (the IMU on the board's top side).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Alignment {
    /// The IMU's axes are the board's.
    Cw0,
    /// Betaflight's `CW90_DEG`.
    Cw90,
    /// Betaflight's `CW180_DEG`.
    Cw180,
    /// Betaflight's `CW270_DEG`.
    Cw270,
}

/// The SpeedyBee F405 V4: Betaflight's `configs/SPEEDYBEEF405V4/config.h`,
/// `#define GYRO_1_ALIGN CW90_DEG` (with `GYRO_1_ALIGN_YAW 900`, the same 90.0° in tenths).
/// (ArduPilot's `hwdef/speedybeef4v4/hwdef.dat` says `ROTATION_PITCH_180_YAW_270`: the same
/// mounting in its z-down body frame.)
pub const SPEEDYBEE_F405_V4: Alignment = Alignment::Cw90;

impl Alignment {
    /// Board axes from IMU axes: `board[i] = sign[i] · imu[index[i]]`.
    pub const fn map(self) -> ([usize; 3], [f32; 3]) {
        match self {
            Alignment::Cw0 => ([0, 1, 2], [1.0, 1.0, 1.0]),
            Alignment::Cw90 => ([1, 0, 2], [1.0, -1.0, 1.0]),
            Alignment::Cw180 => ([0, 1, 2], [-1.0, -1.0, 1.0]),
            Alignment::Cw270 => ([1, 0, 2], [-1.0, 1.0, 1.0]),
        }
    }

    /// A vector in the IMU's axes, in the board's.
    #[inline(always)]
    pub fn to_board(self, v: [f32; 3]) -> [f32; 3] {
        match self {
            Alignment::Cw0 => v,
            Alignment::Cw90 => [v[1], -v[0], v[2]],
            Alignment::Cw180 => [-v[0], -v[1], v[2]],
            Alignment::Cw270 => [-v[1], v[0], v[2]],
        }
    }

    /// Rotates the accelerometer and the gyro of each sample into the board's axes (the F405's
    /// `burst_done`, before the pipeline; 8 kHz, a few moves per sample).
    pub fn apply(self, samples: &mut [ImuSample]) {
        if self == Alignment::Cw0 {
            return;
        }
        for s in samples {
            s.accel_out = self.to_board(s.accel_out);
            s.gyro_rad_s = self.to_board(s.gyro_rad_s);
        }
    }
}

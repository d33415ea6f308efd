//! The body frame of a board with a digital IMU is the board's: its samples are rotated by the
//! board file's alignment, Betaflight's mapping, before the pipeline.

use crate::imu::alignment::{Alignment, SPEEDYBEE_F405_V4};

const ALL: [Alignment; 4] = [
    Alignment::Cw0,
    Alignment::Cw90,
    Alignment::Cw180,
    Alignment::Cw270,
];

/// Betaflight's `alignSensorViaRotation` (`src/main/sensors/boardalignment.c`), written out
/// independently: `CW90_DEG` x = y, y = −x; `CW180_DEG` x = −x, y = −y; `CW270_DEG` x = −y, y = x.
fn betaflight(a: Alignment, [x, y, z]: [f32; 3]) -> [f32; 3] {
    match a {
        Alignment::Cw0 => [x, y, z],
        Alignment::Cw90 => [y, -x, z],
        Alignment::Cw180 => [-x, -y, z],
        Alignment::Cw270 => [-y, x, z],
    }
}

#[test]
fn rotations_are_betaflights_and_proper() {
    let v = [1.5f32, -2.25, 3.0];
    for a in ALL {
        assert_eq!(a.to_board(v), betaflight(a, v), "{a:?}");
        let (index, sign) = a.map();
        let by_map: [f32; 3] = core::array::from_fn(|i| sign[i] * v[index[i]]);
        assert_eq!(by_map, a.to_board(v), "{a:?}");
        // A rotation, not a reflection: the board's z stays the IMU's z and x × y = z.
        let (ex, ey) = (a.to_board([1.0, 0.0, 0.0]), a.to_board([0.0, 1.0, 0.0]));
        let cross = [
            ex[1] * ey[2] - ex[2] * ey[1],
            ex[2] * ey[0] - ex[0] * ey[2],
            ex[0] * ey[1] - ex[1] * ey[0],
        ];
        assert_eq!(cross, a.to_board([0.0, 0.0, 1.0]), "{a:?}");
    }
}

/// The board file's fact (Betaflight's `configs/SPEEDYBEEF405V4/config.h`: `GYRO_1_ALIGN
/// CW90_DEG`), and that the F405 board states it and applies it before its pipeline.
#[test]
fn the_f405_board_rotates_by_its_betaflight_alignment() {
    assert_eq!(SPEEDYBEE_F405_V4, Alignment::Cw90);
    // The IMU's +y is the board's +x (forward); the IMU's +x the board's −y.
    assert_eq!(SPEEDYBEE_F405_V4.to_board([0.0, 1.0, 0.0]), [1.0, 0.0, 0.0]);
    assert_eq!(
        SPEEDYBEE_F405_V4.to_board([1.0, 0.0, 0.0]),
        [0.0, -1.0, 0.0]
    );
    let board = include_str!("../../board/f405.rs");
    assert!(
        board.contains("pub const IMU_ALIGNMENT: Alignment = BOARD.alignment;"),
        "board/f405.rs no longer states its alignment"
    );
    assert_eq!(
        crate::boards::SPEEDYBEE_F405_V4.alignment,
        SPEEDYBEE_F405_V4
    );
    assert!(board.contains(
        "#[cfg(not(any(feature = \"speedybee-v3\", feature = \"speedybee-v5\")))]\npub const BOARD: BoardDesc = boards::SPEEDYBEE_F405_V4;"
    ));
    let bin = include_str!("../../bin/f405.rs");
    let rotate = bin
        .find("board::IMU_ALIGNMENT.apply(&mut samples[..done.samples]);")
        .expect("bin/f405.rs no longer rotates the samples");
    let feed = bin
        .find("push_all(&samples[..done.samples]")
        .expect("the feed");
    assert!(rotate < feed, "rotated after the pipeline saw the samples");
}

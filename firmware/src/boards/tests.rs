//! Each board description against its two reference board files. The facts below are copied from
//! the files (a line each, cited), not the files themselves:
//!
//! - Betaflight: `betaflight/config`, `configs/SPEEDYBEEF405V3/config.h` (commit 3534186),
//!   `configs/SPEEDYBEEF405V4/config.h` (2976772), `configs/SPEEDYBEEF405V5/config.h` (0fa34d4).
//! - ArduPilot: `ArduPilot/ardupilot`, `libraries/AP_HAL_ChibiOS/hwdef/speedybeef4v3/hwdef.dat`
//!   (04dc0b7), `speedybeef4v4/hwdef.dat` (23a98b6), `speedybeef4v5/hwdef.dat` (82c18c1).
//!
//! ArduPilot's IMU rotation is applied by its own formulas (`libraries/AP_Math/vector3.cpp`,
//! `Vector3<T>::rotate`), written out here independently of `imu::alignment`: they take the part's
//! axes to ArduPilot's body frame (x forward, y right, z down); the calibration's board frame is x
//! forward, y left, z up, a roll of 180° from it.

use super::*;

/// What a Betaflight `config.h` says about a board.
struct Betaflight {
    board_name: &'static str,
    /// `USE_ACCGYRO_BMI270` or `USE_GYRO_SPI_ICM42688P`.
    imu_define: &'static str,
    gyro_1_spi_instance: &'static str,
    gyro_1_cs_pin: &'static str,
    gyro_1_exti_pin: &'static str,
    spi1_pins: [&'static str; 3],
    /// `GYRO_1_ALIGN`, or `None` when the file has none (Betaflight's default `CW0_DEG`).
    gyro_1_align: Option<&'static str>,
    led0_pin: &'static str,
    /// `PINIOn_PIN`: user-switched outputs (a BEC, a power pad).
    pinio_pins: &'static [&'static str],
    system_hse_mhz: u32,
}

/// What an ArduPilot `hwdef.dat` says about a board.
struct ArduPilot {
    /// `IMU <driver> SPI:<dev> <rotation>`.
    imu_driver: &'static str,
    imu_rotation: &'static str,
    /// The IMU's `CS` line.
    imu_cs: &'static str,
    spi1_pins: [&'static str; 3],
    /// The pin of `AP_NOTIFY_GPIO_LED_1_PIN`'s GPIO.
    led: &'static str,
    /// Outputs ArduPilot gives relays (power switches), by pin.
    relay_pins: &'static [&'static str],
    oscillator_hz: u32,
}

const BF_V3: Betaflight = Betaflight {
    board_name: "SPEEDYBEEF405V3", // #define BOARD_NAME        SPEEDYBEEF405V3
    imu_define: "USE_ACCGYRO_BMI270", // #define USE_ACCGYRO_BMI270
    gyro_1_spi_instance: "SPI1",   // #define GYRO_1_SPI_INSTANCE SPI1
    gyro_1_cs_pin: "PA4",          // #define GYRO_1_CS_PIN        PA4
    gyro_1_exti_pin: "PC4",        // #define GYRO_1_EXTI_PIN      PC4
    spi1_pins: ["PA5", "PA6", "PA7"], // SPI1_SCK_PIN PA5, SPI1_SDI_PIN PA6, SPI1_SDO_PIN PA7
    gyro_1_align: None,            // (no GYRO_1_ALIGN line)
    led0_pin: "PC8",               // #define LED0_PIN             PC8
    pinio_pins: &["PC3"],          // #define PINIO1_PIN           PC3
    system_hse_mhz: 8,             // #define SYSTEM_HSE_MHZ 8
};
const BF_V4: Betaflight = Betaflight {
    board_name: "SPEEDYBEEF405V4",
    imu_define: "USE_GYRO_SPI_ICM42688P", // #define USE_GYRO_SPI_ICM42688P
    gyro_1_spi_instance: "SPI1",          // #define GYRO_1_SPI_INSTANCE SPI1
    gyro_1_cs_pin: "PA4",                 // #define GYRO_1_CS_PIN PA4
    gyro_1_exti_pin: "PC4",               // #define GYRO_1_EXTI_PIN PC4
    spi1_pins: ["PA5", "PA6", "PA7"],
    gyro_1_align: Some("CW90_DEG"), // #define GYRO_1_ALIGN CW90_DEG
    led0_pin: "PC13",               // #define LED0_PIN PC13
    pinio_pins: &["PB11"],          // #define PINIO1_PIN PB11
    system_hse_mhz: 8,
};
const BF_V5: Betaflight = Betaflight {
    board_name: "SPEEDYBEEF405V5",
    imu_define: "USE_GYRO_SPI_ICM42688P", // #define USE_GYRO_SPI_ICM42688P
    gyro_1_spi_instance: "SPI1",          // #define GYRO_1_SPI_INSTANCE   SPI1
    gyro_1_cs_pin: "PA4",                 // #define GYRO_1_CS_PIN       PA4
    gyro_1_exti_pin: "PC4",               // #define GYRO_1_EXTI_PIN     PC4
    spi1_pins: ["PA5", "PA6", "PA7"],
    gyro_1_align: Some("CW270_DEG"), // #define GYRO_1_ALIGN          CW270_DEG
    led0_pin: "PA15",                // #define LED0_PIN            PA15
    // #define PINIO1_PIN PC13 (BOX_USER1_NAME "9V BEC OFF"), #define PINIO2_PIN PC14
    // (BOX_USER2_NAME "PROG PWR SWITCH")
    pinio_pins: &["PC13", "PC14"],
    system_hse_mhz: 8,
};

const AP_V3: ArduPilot = ArduPilot {
    imu_driver: "BMI270", // IMU BMI270 SPI:bmi270 ROTATION_ROLL_180
    imu_rotation: "ROTATION_ROLL_180",
    imu_cs: "PA4",                    // PA4 BMI270_CS CS
    spi1_pins: ["PA5", "PA6", "PA7"], // PA5 SPI1_SCK, PA6 SPI1_MISO, PA7 SPI1_MOSI
    led: "PC8",                       // PC8 LED_BLUE OUTPUT LOW GPIO(0); AP_NOTIFY_GPIO_LED_1_PIN 0
    relay_pins: &[],
    oscillator_hz: 8_000_000, // OSCILLATOR_HZ 8000000
};
const AP_V4: ArduPilot = ArduPilot {
    imu_driver: "Invensensev3", // IMU Invensensev3 SPI:imu1 ROTATION_PITCH_180_YAW_270
    imu_rotation: "ROTATION_PITCH_180_YAW_270",
    imu_cs: "PA4", // PA4 GYRO1_CS CS
    spi1_pins: ["PA5", "PA6", "PA7"],
    led: "PC13",           // PC13 LED0 OUTPUT LOW GPIO(90); AP_NOTIFY_GPIO_LED_1_PIN 90
    relay_pins: &["PB14"], // PB14 CAMERA1 OUTPUT GPIO(70) LOW; RELAY2_PIN_DEFAULT 70
    oscillator_hz: 8_000_000,
};
const AP_V5: ArduPilot = ArduPilot {
    imu_driver: "Invensensev3", // IMU Invensensev3 SPI:imu1 ROTATION_PITCH_180_YAW_90
    imu_rotation: "ROTATION_PITCH_180_YAW_90",
    imu_cs: "PA4", // PA4 GYRO1_CS CS
    spi1_pins: ["PA5", "PA6", "PA7"],
    led: "PA15", // PA15 LED0 OUTPUT LOW GPIO(90); AP_NOTIFY_GPIO_LED_1_PIN 90
    // PB8 CAMERA1 (RELAY2), PC13 VTX_PWR (RELAY3), PC14 PWR_SWITCH (RELAY4)
    relay_pins: &["PB8", "PC13", "PC14"],
    oscillator_hz: 8_000_000,
};

/// "PC13" → PC13.
fn pin(name: &str) -> Pin {
    let b = name.as_bytes();
    assert_eq!(b[0], b'P', "{name}");
    Pin::new(b[1], name[2..].parse().unwrap())
}

/// ArduPilot's `Vector3<T>::rotate` for the rotations these boards use (AP_Math/vector3.cpp).
fn ardupilot_rotate(rotation: &str, v: [f32; 3]) -> [f32; 3] {
    let [x, y, z] = v;
    match rotation {
        // case ROTATION_ROLL_180: { y = -y; z = -z; }
        "ROTATION_ROLL_180" => [x, -y, -z],
        // case ROTATION_PITCH_180_YAW_270: { tmp = x; x = y; y = tmp; z = -z; }
        "ROTATION_PITCH_180_YAW_270" => [y, x, -z],
        // case ROTATION_PITCH_180_YAW_90: { tmp = x; x = -y; y = -tmp; z = -z; }
        "ROTATION_PITCH_180_YAW_90" => [-y, -x, -z],
        other => panic!("rotation {other} not transcribed"),
    }
}

/// Betaflight's `alignSensorViaRotation` (`src/main/sensors/boardalignment.c`) for the yaw-only
/// alignments, as its switch writes them.
fn betaflight_rotate(align: Option<&str>, v: [f32; 3]) -> [f32; 3] {
    let [x, y, z] = v;
    match align.unwrap_or("CW0_DEG") {
        "CW0_DEG" => [x, y, z],
        // case CW90_DEG: dest[X] = y; dest[Y] = -x; dest[Z] = z;
        "CW90_DEG" => [y, -x, z],
        // case CW270_DEG: dest[X] = -y; dest[Y] = x; dest[Z] = z;
        "CW270_DEG" => [-y, x, z],
        other => panic!("alignment {other} not transcribed"),
    }
}

fn cases() -> [(&'static BoardDesc, Betaflight, ArduPilot); 3] {
    [
        (&SPEEDYBEE_F405_V3, BF_V3, AP_V3),
        (&SPEEDYBEE_F405_V4, BF_V4, AP_V4),
        (&SPEEDYBEE_F405_V5, BF_V5, AP_V5),
    ]
}

#[test]
fn each_board_matches_its_betaflight_config() {
    for (d, bf, _) in cases() {
        assert_eq!(d.name, bf.board_name);
        let part = match bf.imu_define {
            "USE_ACCGYRO_BMI270" => ImuPart::Bmi270,
            "USE_GYRO_SPI_ICM42688P" => ImuPart::Icm42688P,
            other => panic!("{other}"),
        };
        assert_eq!(d.imu, part, "{}", d.name);
        assert_eq!(format!("SPI{}", d.imu_spi_instance), bf.gyro_1_spi_instance);
        assert_eq!(d.imu_cs, pin(bf.gyro_1_cs_pin), "{}", d.name);
        assert_eq!(d.imu_int, pin(bf.gyro_1_exti_pin), "{}", d.name);
        assert_eq!(d.spi_pins, bf.spi1_pins.map(pin), "{}", d.name);
        assert_eq!(d.led, pin(bf.led0_pin), "{}", d.name);
        assert_eq!(d.hse_hz, bf.system_hse_mhz * 1_000_000, "{}", d.name);
        for p in bf.pinio_pins {
            assert!(
                d.never_touch.iter().any(|r| r.pin == pin(p)),
                "{}: Betaflight's PINIO {p} is not reserved",
                d.name
            );
        }
        for v in [
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, 0.0, 1.0],
            [0.3, -0.5, 0.8],
        ] {
            assert_eq!(
                d.alignment.to_board(v),
                betaflight_rotate(bf.gyro_1_align, v),
                "{}",
                d.name
            );
        }
    }
}

#[test]
fn each_board_matches_its_ardupilot_hwdef() {
    for (d, _, ap) in cases() {
        let part = match ap.imu_driver {
            "BMI270" => ImuPart::Bmi270,
            "Invensensev3" => ImuPart::Icm42688P,
            other => panic!("{other}"),
        };
        assert_eq!(d.imu, part, "{}", d.name);
        assert_eq!(d.imu_cs, pin(ap.imu_cs), "{}", d.name);
        assert_eq!(d.spi_pins, ap.spi1_pins.map(pin), "{}", d.name);
        assert_eq!(d.led, pin(ap.led), "{}", d.name);
        assert_eq!(d.hse_hz, ap.oscillator_hz, "{}", d.name);
        for p in ap.relay_pins {
            assert!(
                !d.used_pins().contains(&pin(p)),
                "{}: ArduPilot's relay output {p} is driven by the firmware",
                d.name
            );
        }
        // ArduPilot's body frame (forward, right, down) rolled by 180° is the board frame.
        for v in [
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, 0.0, 1.0],
            [0.3, -0.5, 0.8],
        ] {
            let [x, y, z] = ardupilot_rotate(ap.imu_rotation, v);
            assert_eq!(d.alignment.to_board(v), [x, -y, -z], "{}", d.name);
        }
    }
}

/// The V5's status LED is PA15; PC13 — the V4's LED — switches its 9 V BEC and is never driven.
#[test]
fn the_v5_never_drives_its_bec_switch() {
    let d = SPEEDYBEE_F405_V5;
    assert_eq!(d.check(), Ok(()));
    assert!(!d.used_pins().contains(&Pin::new(b'C', 13)));
    let with_v4_led = BoardDesc {
        led: SPEEDYBEE_F405_V4.led,
        ..d
    };
    assert_eq!(
        with_v4_led.check(),
        Err(BoardError::TouchesReserved(Pin::new(b'C', 13)))
    );
}

#[test]
fn a_description_with_a_pin_twice_or_a_fast_bus_is_refused() {
    let d = BoardDesc {
        imu_int: SPEEDYBEE_F405_V3.imu_cs,
        ..SPEEDYBEE_F405_V3
    };
    assert_eq!(d.check(), Err(BoardError::PinTwice(Pin::new(b'A', 4))));
    // The V3's BMI270 (10 MHz) on the V4's 21 MHz bus.
    let d = BoardDesc {
        imu_spi: SPEEDYBEE_F405_V4.imu_spi,
        ..SPEEDYBEE_F405_V3
    };
    assert_eq!(d.check(), Err(BoardError::BusForAnotherPart));
    let d = BoardDesc {
        imu_spi: SpiBus {
            asked_hz: 21_000_000,
            ..BMI270_BUS
        },
        ..SPEEDYBEE_F405_V3
    };
    assert!(matches!(d.check(), Err(BoardError::Bus(_))));
}

/// The F405 firmware is built from the description its feature selects, and takes its LED, IMU
/// rotation, crystal and bus from it (no pin of its own).
#[test]
fn the_f405_firmware_is_built_from_its_description() {
    let board = include_str!("../board/f405.rs");
    for line in [
        "pub const BOARD: BoardDesc = boards::SPEEDYBEE_F405_V3;",
        "pub const BOARD: BoardDesc = boards::SPEEDYBEE_F405_V4;",
        "pub const BOARD: BoardDesc = boards::SPEEDYBEE_F405_V5;",
        "pub const IMU_ALIGNMENT: Alignment = BOARD.alignment;",
        "pub const HSE_HZ: u32 = BOARD.hse_hz;",
        "const _: () = assert!(BOARD.check().is_ok());",
    ] {
        assert!(board.contains(line), "board/f405.rs lacks `{line}`");
    }
    assert!(
        !board.contains("GPIOC::ptr()"),
        "board/f405.rs drives a GPIO port of its own"
    );
    // Both binaries: the ICM-42688-P's (V4, V5) and the BMI270's (V3).
    for (name, bin) in [
        ("bin/f405.rs", include_str!("../bin/f405.rs")),
        ("bin/f405_bmi270.rs", include_str!("../bin/f405_bmi270.rs")),
    ] {
        assert!(!bin.contains(".pc13"), "{name} configures PC13 itself");
        for line in [
            "board::init_led()",
            "&board::BOARD.imu_spi",
            "board::IMU_ALIGNMENT.apply(",
            "matches!(board::BOARD.imu, ImuPart::",
        ] {
            assert!(bin.contains(line), "{name} lacks `{line}`");
        }
    }
}

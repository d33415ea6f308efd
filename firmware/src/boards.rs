//! Boards as data: one description per flight controller — its IMU and the bus it sits on, the
//! chip-select and interrupt pins, how the IMU is turned on the board, the status LED, the pins
//! that must never be driven, the crystal — from which the F405 firmware is built (feature
//! `board-f405` with `speedybee-v3` / `speedybee-v5`, the V4 without either; `board::f405::BOARD`).
//!
//! The facts are the boards' Betaflight hardware definitions (`betaflight/config`,
//! `configs/SPEEDYBEEF405V3|V4|V5/config.h`) and ArduPilot's (`libraries/AP_HAL_ChibiOS/hwdef/
//! speedybeef4v3|v4|v5/hwdef.dat`); the PC tests (`boards::tests`) compare every description with
//! both, the IMU rotation included (ArduPilot's rotations are applied by its own formulas there).
//!
//! [`BoardDesc::check`] is evaluated at compile time for the board built (`board::f405`): a
//! description whose LED is a pin never to touch, whose pins collide, or whose IMU bus runs above
//! the part's SPI clock does not build.

use crate::clock_tree::{f405::PCLK2_HZ, SpiBus, SpiPins, BMI270_SPI_MAX_HZ, ICM42688_SPI_MAX_HZ};
use crate::imu::alignment::{self, Alignment};

/// A GPIO pin: port letter (`b'A'`…) and number (0–15).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Pin {
    /// Port letter, ASCII upper case.
    pub port: u8,
    /// Pin number in the port.
    pub n: u8,
}

impl Pin {
    /// `Pin::new(b'C', 13)` is PC13.
    pub const fn new(port: u8, n: u8) -> Pin {
        Pin { port, n }
    }

    /// Same pin (`==` is not `const`).
    pub const fn is(self, other: Pin) -> bool {
        self.port == other.port && self.n == other.n
    }

    /// The port's index from A (GPIOA 0, GPIOB 1, …): its registers lie 0x400 apart.
    pub const fn port_index(self) -> u32 {
        (self.port - b'A') as u32
    }
}

/// The inertial part a board carries.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ImuPart {
    /// TDK InvenSense ICM-42688-P (`imu::icm42688`).
    Icm42688P,
    /// Bosch BMI270 (`imu::bmi270`).
    Bmi270,
}

impl ImuPart {
    /// The part's highest SPI clock, Hz.
    pub const fn spi_max_hz(self) -> u32 {
        match self {
            ImuPart::Icm42688P => ICM42688_SPI_MAX_HZ,
            ImuPart::Bmi270 => BMI270_SPI_MAX_HZ,
        }
    }
}

/// A pin the firmware must never drive, and why.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Reserved {
    /// The pin.
    pub pin: Pin,
    /// What it switches on the board.
    pub why: &'static str,
}

/// One flight controller.
#[derive(Clone, Copy, Debug)]
pub struct BoardDesc {
    /// As Betaflight names it (`BOARD_NAME`).
    pub name: &'static str,
    /// The IMU.
    pub imu: ImuPart,
    /// SPI instance of the IMU (1 = SPI1; the firmware's DMA streams are SPI1's).
    pub imu_spi_instance: u8,
    /// The IMU's SPI clock, computed with the HAL's rules and checked against the part.
    pub imu_spi: SpiBus,
    /// SCK, MISO, MOSI.
    pub spi_pins: [Pin; 3],
    /// The IMU's chip select (active low).
    pub imu_cs: Pin,
    /// The IMU's interrupt line (rising edge).
    pub imu_int: Pin,
    /// How the IMU is turned on the board (samples are rotated into the board's axes).
    pub alignment: Alignment,
    /// The status LED.
    pub led: Pin,
    /// The LED is lit when its pin is low (Betaflight's default without `LED0_INVERTED`).
    pub led_lit_low: bool,
    /// Pins that switch power or peripherals on the board: never configured, never written.
    pub never_touch: &'static [Reserved],
    /// The crystal, Hz.
    pub hse_hz: u32,
}

/// Why a description was refused.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BoardError {
    /// The LED, CS, interrupt or an SPI pin is one never to touch.
    TouchesReserved(Pin),
    /// Two of the firmware's pins are the same.
    PinTwice(Pin),
    /// The IMU bus's table was refused (clock above the part's, slow pins).
    Bus(crate::clock_tree::BusError),
    /// The bus table names another part's limit.
    BusForAnotherPart,
    /// Only SPI1 has DMA streams wired in the firmware.
    NotSpi1,
}

impl BoardDesc {
    /// The pins the firmware drives or reads.
    pub const fn used_pins(&self) -> [Pin; 6] {
        [
            self.spi_pins[0],
            self.spi_pins[1],
            self.spi_pins[2],
            self.imu_cs,
            self.imu_int,
            self.led,
        ]
    }

    /// The description is consistent: no used pin reserved or used twice, the bus within the part.
    pub const fn check(&self) -> Result<(), BoardError> {
        if self.imu_spi_instance != 1 {
            return Err(BoardError::NotSpi1);
        }
        if self.imu_spi.device_max_hz != self.imu.spi_max_hz() {
            return Err(BoardError::BusForAnotherPart);
        }
        if let Err(e) = self.imu_spi.check() {
            return Err(BoardError::Bus(e));
        }
        let used = self.used_pins();
        let mut i = 0;
        while i < used.len() {
            let mut j = 0;
            while j < self.never_touch.len() {
                if used[i].is(self.never_touch[j].pin) {
                    return Err(BoardError::TouchesReserved(used[i]));
                }
                j += 1;
            }
            let mut k = i + 1;
            while k < used.len() {
                if used[i].is(used[k]) {
                    return Err(BoardError::PinTwice(used[i]));
                }
                k += 1;
            }
            i += 1;
        }
        Ok(())
    }
}

/// SPI1 on every SpeedyBee F405: PA5 SCK, PA6 MISO (`SPI1_SDI_PIN`), PA7 MOSI (`SPI1_SDO_PIN`).
const SPEEDYBEE_SPI1: [Pin; 3] = [Pin::new(b'A', 5), Pin::new(b'A', 6), Pin::new(b'A', 7)];

/// SPI1 at 21 MHz (84 MHz / 4) for the ICM-42688-P (24 MHz).
pub const ICM42688_BUS: SpiBus = SpiBus {
    device: "ICM-42688-P",
    apb_hz: PCLK2_HZ,
    asked_hz: 21_000_000,
    device_max_hz: ICM42688_SPI_MAX_HZ,
    pins: SpiPins::VERY_HIGH,
};

/// SPI1 at 5.25 MHz for the BMI270 (10 MHz): the HAL's divider from 84 / asked, so 10 MHz asked
/// gives 84 / 10 = 8 → ÷8 = 10.5 MHz, over the limit; 5.25 MHz asked gives ÷16.
pub const BMI270_BUS: SpiBus = SpiBus {
    device: "BMI270",
    apb_hz: PCLK2_HZ,
    asked_hz: 5_250_000,
    device_max_hz: BMI270_SPI_MAX_HZ,
    pins: SpiPins::VERY_HIGH,
};

/// SpeedyBee F405 V3: BMI270 on SPI1, LED PC8; PC3 is PINIO1 (Betaflight `PINIO1_PIN PC3`).
pub const SPEEDYBEE_F405_V3: BoardDesc = BoardDesc {
    name: "SPEEDYBEEF405V3",
    imu: ImuPart::Bmi270,
    imu_spi_instance: 1,
    imu_spi: BMI270_BUS,
    spi_pins: SPEEDYBEE_SPI1,
    imu_cs: Pin::new(b'A', 4),
    imu_int: Pin::new(b'C', 4),
    // No GYRO_1_ALIGN in its config.h: Betaflight's default, CW0.
    alignment: Alignment::Cw0,
    led: Pin::new(b'C', 8),
    led_lit_low: true,
    never_touch: &[Reserved {
        pin: Pin::new(b'C', 3),
        why: "PINIO1 (user switch)",
    }],
    hse_hz: 8_000_000,
};

/// SpeedyBee F405 V4: ICM-42688-P on SPI1 turned CW90, LED PC13; PB11 is PINIO1.
pub const SPEEDYBEE_F405_V4: BoardDesc = BoardDesc {
    name: "SPEEDYBEEF405V4",
    imu: ImuPart::Icm42688P,
    imu_spi_instance: 1,
    imu_spi: ICM42688_BUS,
    spi_pins: SPEEDYBEE_SPI1,
    imu_cs: Pin::new(b'A', 4),
    imu_int: Pin::new(b'C', 4),
    alignment: alignment::SPEEDYBEE_F405_V4,
    led: Pin::new(b'C', 13),
    led_lit_low: true,
    never_touch: &[Reserved {
        pin: Pin::new(b'B', 11),
        why: "PINIO1 (user switch)",
    }],
    hse_hz: 8_000_000,
};

/// SpeedyBee F405 V5: the V4's IMU pins, the IMU turned CW270, LED PA15; PC13 switches the 9 V
/// BEC (PINIO1, "9V BEC OFF") and PC14 the programmable power pads (PINIO2): never toggled.
pub const SPEEDYBEE_F405_V5: BoardDesc = BoardDesc {
    name: "SPEEDYBEEF405V5",
    imu: ImuPart::Icm42688P,
    imu_spi_instance: 1,
    imu_spi: ICM42688_BUS,
    spi_pins: SPEEDYBEE_SPI1,
    imu_cs: Pin::new(b'A', 4),
    imu_int: Pin::new(b'C', 4),
    alignment: Alignment::Cw270,
    led: Pin::new(b'A', 15),
    led_lit_low: true,
    never_touch: &[
        Reserved {
            pin: Pin::new(b'C', 13),
            why: "PINIO1: the 9 V BEC switch",
        },
        Reserved {
            pin: Pin::new(b'C', 14),
            why: "PINIO2: the programmable power switch",
        },
    ],
    hse_hz: 8_000_000,
};

/// Every described board.
pub const BOARDS: [BoardDesc; 3] = [SPEEDYBEE_F405_V3, SPEEDYBEE_F405_V4, SPEEDYBEE_F405_V5];

const _: () = assert!(SPEEDYBEE_F405_V3.check().is_ok());
const _: () = assert!(SPEEDYBEE_F405_V4.check().is_ok());
const _: () = assert!(SPEEDYBEE_F405_V5.check().is_ok());

#[cfg(test)]
mod tests;

//! The STM32 boards' SPI buses as data, checked at compile time (the `const` assertions at the end)
//! and by the PC tests: the output speed of every SPI pin. The board code sets its pins from these
//! tables through one helper (`board::stm32_common::spi1`), so what is checked is what runs.
//!
//! **Pin speed.** A GPIO's output speed (GPIOx_OSPEEDR) resets to low (00) on PA5–PA7, which both
//! boards use for SPI1. stm32f4xx-hal 0.23 warns (`src/spi.rs:302-303`, on `SpiExt::spi`): "Depending
//! on `freq` you may need to set GPIO speed for `pins` (the `Speed::Low` is default for GPIO) before
//! create `Spi` instance. Otherwise it may lead to the 'wrong last bit in every received byte'
//! problem" (the review cites ST's errata ES0182 §2.5.2 for it; not re-checked here). The model of
//! that fault is `imu::sim::LastBitFault`. Every SPI pin is therefore set to high or very high speed
//! before the HAL takes it, and [`SpiBus::check`] refuses a table with a slower pin.

/// A GPIO output speed (GPIOx_OSPEEDR: 00 low, 01 medium, 10 high, 11 very high).
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum PinSpeed {
    /// 00, every pin's reset value except the debug pins.
    Low = 0,
    /// 01.
    Medium = 1,
    /// 10 ("fast" in the reference manuals).
    High = 2,
    /// 11.
    VeryHigh = 3,
}

/// The slowest speed an SPI pin may have (the HAL's documentation: high or very high).
pub const SPI_PIN_MIN_SPEED: PinSpeed = PinSpeed::High;

/// One of a bus's three pins.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SpiPin {
    /// Clock.
    Sck,
    /// Master in.
    Miso,
    /// Master out.
    Mosi,
}

/// The output speed of each pin of an SPI bus.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SpiPins {
    /// Clock.
    pub sck: PinSpeed,
    /// Master in.
    pub miso: PinSpeed,
    /// Master out.
    pub mosi: PinSpeed,
}

impl SpiPins {
    /// Every pin at its reset speed (what the boards had before their pins were set).
    pub const AT_RESET: SpiPins = SpiPins {
        sck: PinSpeed::Low,
        miso: PinSpeed::Low,
        mosi: PinSpeed::Low,
    };

    /// Every pin at very high speed.
    pub const VERY_HIGH: SpiPins = SpiPins {
        sck: PinSpeed::VeryHigh,
        miso: PinSpeed::VeryHigh,
        mosi: PinSpeed::VeryHigh,
    };
}

/// An SPI bus of a board, as its set-up uses it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SpiBus {
    /// The part on the other end (for messages).
    pub device: &'static str,
    /// Its pins' output speeds.
    pub pins: SpiPins,
}

/// Why a bus's table was refused.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BusError {
    /// A pin is slower than [`SPI_PIN_MIN_SPEED`].
    PinTooSlow {
        /// Which pin.
        pin: SpiPin,
        /// Its speed in the table.
        speed: PinSpeed,
    },
}

impl SpiBus {
    /// Checks the table: every pin at [`SPI_PIN_MIN_SPEED`] or faster.
    pub const fn check(&self) -> Result<(), BusError> {
        let pins = [
            (SpiPin::Sck, self.pins.sck),
            (SpiPin::Miso, self.pins.miso),
            (SpiPin::Mosi, self.pins.mosi),
        ];
        let mut i = 0;
        while i < pins.len() {
            let (pin, speed) = pins[i];
            if (speed as u8) < (SPI_PIN_MIN_SPEED as u8) {
                return Err(BusError::PinTooSlow { pin, speed });
            }
            i += 1;
        }
        Ok(())
    }
}

/// The STM32F446RE Nucleo-64 (`board::stm32f4`).
pub mod nucleo {
    use super::*;

    /// SPI1 (PA5 SCK, PA6 MISO, PA7 MOSI) to the L3GD20H / I3G4250D gyro.
    pub const GYRO_SPI: SpiBus = SpiBus {
        device: "L3GD20H",
        pins: SpiPins::VERY_HIGH,
    };
}

/// The STM32F405 flight controller (`board::f405`).
pub mod f405 {
    use super::*;

    /// SPI1 (PA5 SCK, PA6 MISO, PA7 MOSI) to the ICM-42688-P.
    pub const IMU_SPI: SpiBus = SpiBus {
        device: "ICM-42688-P",
        pins: SpiPins::VERY_HIGH,
    };
}

/// Every board's SPI buses (the PC test goes through all of them).
pub const BOARD_SPI_BUSES: [SpiBus; 2] = [nucleo::GYRO_SPI, f405::IMU_SPI];

// A board whose table is refused does not build.
const _: () = assert!(nucleo::GYRO_SPI.check().is_ok());
const _: () = assert!(f405::IMU_SPI.check().is_ok());

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_board_spi_pin_is_fast() {
        for bus in BOARD_SPI_BUSES {
            assert_eq!(bus.check(), Ok(()), "{}", bus.device);
        }
    }

    #[test]
    fn a_pin_left_at_reset_speed_is_refused() {
        let bus = SpiBus {
            device: "test",
            pins: SpiPins::AT_RESET,
        };
        assert_eq!(
            bus.check(),
            Err(BusError::PinTooSlow {
                pin: SpiPin::Sck,
                speed: PinSpeed::Low
            })
        );
        // Medium is not enough either; one slow pin among fast ones is found.
        let bus = SpiBus {
            device: "test",
            pins: SpiPins {
                miso: PinSpeed::Medium,
                ..SpiPins::VERY_HIGH
            },
        };
        assert_eq!(
            bus.check(),
            Err(BusError::PinTooSlow {
                pin: SpiPin::Miso,
                speed: PinSpeed::Medium
            })
        );
        let high = SpiBus {
            device: "test",
            pins: SpiPins {
                sck: PinSpeed::High,
                miso: PinSpeed::High,
                mosi: PinSpeed::High,
            },
        };
        assert_eq!(high.check(), Ok(()));
    }
}

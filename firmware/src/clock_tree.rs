//! The STM32 boards' serial clocks and SPI pins as data, checked at compile time (the `const`
//! assertions at the end) and by the PC tests: every SPI, ADC and USART clock computed with the
//! HAL's own rules from the clock tree, against the limit of the part on the other end, and the
//! output speed of every SPI pin. The board code sets up its buses from these tables through one
//! helper (`board::stm32_common::spi1`, which also compares the APB clock the HAL reports with the
//! table's at boot), so what is checked is what runs.
//!
//! **The HAL's rules** (stm32f4xx-hal 0.23, read from its source):
//!
//! - APB prescaler (`src/rcc/f4/mod.rs:393-425`, `Rcc::freeze`): the clock asked for, or by default
//!   the smaller of the chip's APB limit and HCLK; the divider from `ceil(hclk / asked)`: 1 → 1,
//!   2 → 2, 3..=5 → 4, 6..=11 → 8, else 16 ([`apb_hz`]).
//! - SPI baud rate (`src/spi.rs:664-674`, `Spi::pre_init`): BR from the *integer* ratio
//!   `apb / asked`: 1..=2 → ÷2, 3..=5 → ÷4, 6..=11 → ÷8, 12..=23 → ÷16, 24..=47 → ÷32, 48..=95 →
//!   ÷64, 96..=191 → ÷128, else ÷256 ([`spi_hz`]). This is *not* "the smallest divider whose
//!   clock is at most the one asked": 90 MHz / 8 MHz = 11 gives ÷8, 11.25 MHz, above the 8 MHz
//!   asked. A ratio of 0 (asked above the APB clock) panics in the HAL; [`SpiBus::check`]
//!   refuses it.
//! - USART baud rate (`src/serial.rs:345-353`, `calculate_brr`): with 16× oversampling when
//!   `pclk / 16 >= baud` (both boards' case), BRR = `(pclk + baud / 2) / baud`, so the baud rate
//!   is `pclk / BRR` ([`usart_baud`]).
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

/// The APB clock `Rcc::freeze` gives (stm32f4xx-hal 0.23 `src/rcc/f4/mod.rs:393-425`): `asked`,
/// or 0 for its default, the smaller of `max` and `hclk`; divided from HCLK by 1, 2, 4, 8 or 16.
pub const fn apb_hz(hclk: u32, asked: u32, max: u32) -> u32 {
    let want = if asked == 0 {
        if max < hclk {
            max
        } else {
            hclk
        }
    } else {
        asked
    };
    let ppre = match hclk.div_ceil(want) {
        0 | 1 => 1,
        2 => 2,
        3..=5 => 4,
        6..=11 => 8,
        _ => 16,
    };
    hclk / ppre
}

/// The SPI clock the HAL sets for `asked` on a bus clocked at `apb` (stm32f4xx-hal 0.23
/// `src/spi.rs:664-674`); 0 where the HAL would panic (`asked` 0 or above `apb`).
pub const fn spi_hz(apb: u32, asked: u32) -> u32 {
    if asked == 0 || asked > apb {
        return 0;
    }
    let br = match apb / asked {
        0..=2 => 0,
        3..=5 => 1,
        6..=11 => 2,
        12..=23 => 3,
        24..=47 => 4,
        48..=95 => 5,
        96..=191 => 6,
        _ => 7,
    };
    apb >> (br + 1)
}

/// The baud rate the HAL sets for `baud` on a USART clocked at `pclk`, with 16× oversampling
/// (stm32f4xx-hal 0.23 `src/serial.rs:345-353`); 0 where the HAL would not oversample by 16.
pub const fn usart_baud(pclk: u32, baud: u32) -> u32 {
    if baud == 0 || pclk / 16 < baud {
        return 0;
    }
    pclk / ((pclk + baud / 2) / baud)
}

/// |actual − wanted| / wanted, in parts per million.
pub const fn error_ppm(actual: u32, wanted: u32) -> u32 {
    let d = actual.abs_diff(wanted) as u64;
    (d * 1_000_000 / wanted as u64) as u32
}

/// An SPI bus of a board, as its set-up uses it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SpiBus {
    /// The part on the other end (for messages).
    pub device: &'static str,
    /// The bus's APB clock, Hz (SPI1: APB2).
    pub apb_hz: u32,
    /// The SCK frequency asked of the HAL, Hz.
    pub asked_hz: u32,
    /// The part's highest SCK frequency, Hz.
    pub device_max_hz: u32,
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
    /// The frequency asked is 0 or above the APB clock (the HAL would panic).
    Unreachable,
    /// The HAL's clock for the frequency asked is above the part's limit.
    AboveDevice {
        /// The SCK frequency the HAL sets, Hz.
        actual_hz: u32,
        /// The part's limit, Hz.
        max_hz: u32,
    },
}

impl SpiBus {
    /// The SCK frequency the HAL sets for this bus, Hz.
    pub const fn actual_hz(&self) -> u32 {
        spi_hz(self.apb_hz, self.asked_hz)
    }

    /// Checks the table: the HAL's clock within the part's limit, every pin at
    /// [`SPI_PIN_MIN_SPEED`] or faster.
    pub const fn check(&self) -> Result<(), BusError> {
        let actual_hz = self.actual_hz();
        if actual_hz == 0 {
            return Err(BusError::Unreachable);
        }
        if actual_hz > self.device_max_hz {
            return Err(BusError::AboveDevice {
                actual_hz,
                max_hz: self.device_max_hz,
            });
        }
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

/// The L3GD20H's (and I3G4250D's) highest SPI clock, Hz (datasheets' SPI slave timing: f_c(SPC)
/// 10 MHz).
pub const L3GD20H_SPI_MAX_HZ: u32 = 10_000_000;
/// The ICM-42688-P's highest SPI clock, Hz (DS-000347: 24 MHz; Betaflight's
/// `accgyro_spi_icm426xx.c` line 56, `ICM426XX_MAX_SPI_CLK_HZ 24000000`).
pub const ICM42688_SPI_MAX_HZ: u32 = 24_000_000;
/// The BMI270's highest SPI clock, Hz (BST-BMI270-DS000 §"Electrical specification", SPI clock
/// 10 MHz; Betaflight's `accgyro_spi_bmi270.c`, `BMI270_MAX_SPI_CLK_HZ 10000000`).
pub const BMI270_SPI_MAX_HZ: u32 = 10_000_000;
/// The LSM6DSO's highest SPI clock, Hz (DS12140 Table "SPI slave timing values": f_c(SPC) 10 MHz).
pub const LSM6DSO_SPI_MAX_HZ: u32 = 10_000_000;
/// A USART's baud rate error allowed on this side, ppm: half of the 3.41 % a receiver with 16×
/// oversampling and a fractional divider tolerates (RM0390, USART receiver's tolerance to clock
/// deviation), the other half left to the other end.
pub const USART_ERROR_MAX_PPM: u32 = 17_000;

/// The STM32F446RE Nucleo-64 (`board::stm32f4`): HSE 8 MHz → PLL → SYSCLK 180 MHz, AHB ÷1.
pub mod nucleo {
    use super::*;

    /// Core clock and HCLK, Hz.
    pub const SYSCLK_HZ: u32 = 180_000_000;
    /// APB2 clock, Hz: asked of the HAL as 90 MHz (the F446's APB2 limit, SYSCLK_MAX / 2).
    pub const PCLK2_HZ: u32 = apb_hz(SYSCLK_HZ, 90_000_000, 90_000_000);
    /// APB1 clock, Hz: the HAL's default, its APB1 limit 45 MHz.
    pub const PCLK1_HZ: u32 = apb_hz(SYSCLK_HZ, 0, 45_000_000);
    /// ADC prescaler (ADC_CCR.ADCPRE: PCLK2 divided by 4).
    pub const ADC_PRESCALER: u32 = 4;
    /// ADC clock, Hz.
    pub const ADC_CLOCK_HZ: u32 = PCLK2_HZ / ADC_PRESCALER;
    /// The STM32F446's highest ADC clock at V_DDA 2.4–3.6 V (datasheet DS10693), Hz.
    pub const ADC_CLOCK_MAX_HZ: u32 = 36_000_000;
    /// USART2 (APB1) baud rate asked.
    pub const BAUD: u32 = 921_600;
    /// USART2's actual baud rate.
    pub const BAUD_ACTUAL: u32 = usart_baud(PCLK1_HZ, BAUD);

    /// SPI1 (PA5 SCK, PA6 MISO, PA7 MOSI, APB2) to the L3GD20H / I3G4250D gyro. 5.625 MHz asked
    /// (90 MHz / 16, the fastest the HAL can give within the gyro's 10 MHz): the 8 MHz asked
    /// before gave 90 / 8 = 11 → ÷8 = 11.25 MHz.
    pub const GYRO_SPI: SpiBus = SpiBus {
        device: "L3GD20H",
        apb_hz: PCLK2_HZ,
        asked_hz: 5_625_000,
        device_max_hz: L3GD20H_SPI_MAX_HZ,
        pins: SpiPins::VERY_HIGH,
    };
}

/// The STM32F405 flight controller (`board::f405`): HSE 8 MHz → PLL → SYSCLK 168 MHz, AHB ÷1.
pub mod f405 {
    use super::*;

    /// Core clock and HCLK, Hz.
    pub const SYSCLK_HZ: u32 = 168_000_000;
    /// APB2 clock, Hz: the HAL's default, the F405's APB2 limit 84 MHz.
    pub const PCLK2_HZ: u32 = apb_hz(SYSCLK_HZ, 0, 84_000_000);

    /// SPI1 (PA5 SCK, PA6 MISO, PA7 MOSI, APB2) to the ICM-42688-P: 84 / 21 = 4 → ÷4 = 21 MHz.
    pub const IMU_SPI: SpiBus = SpiBus {
        device: "ICM-42688-P",
        apb_hz: PCLK2_HZ,
        asked_hz: 21_000_000,
        device_max_hz: ICM42688_SPI_MAX_HZ,
        pins: SpiPins::VERY_HIGH,
    };

    /// SPI1 to an LSM6DSO (10 MHz): 84 / 5.25 = 16 → ÷16 = 5.25 MHz. 10 MHz asked would give
    /// 84 / 10 = 8 → ÷8 = 10.5 MHz, over the part's limit; 21 MHz (the ICM's bus) twice it.
    pub const LSM6DSO_SPI: SpiBus = SpiBus {
        device: "LSM6DSO",
        apb_hz: PCLK2_HZ,
        asked_hz: 5_250_000,
        device_max_hz: LSM6DSO_SPI_MAX_HZ,
        pins: SpiPins::VERY_HIGH,
    };
}

/// Every board's SPI buses (the PC test goes through all of them), the described flight
/// controllers' IMU buses (`boards`) included.
pub const BOARD_SPI_BUSES: [SpiBus; 6] = [
    nucleo::GYRO_SPI,
    f405::IMU_SPI,
    f405::LSM6DSO_SPI,
    crate::boards::SPEEDYBEE_F405_V3.imu_spi,
    crate::boards::SPEEDYBEE_F405_V4.imu_spi,
    crate::boards::SPEEDYBEE_F405_V5.imu_spi,
];

// A board whose table is refused does not build.
const _: () = assert!(nucleo::GYRO_SPI.check().is_ok());
const _: () = assert!(f405::IMU_SPI.check().is_ok());
const _: () = assert!(f405::LSM6DSO_SPI.check().is_ok());
const _: () = assert!(nucleo::ADC_CLOCK_HZ <= nucleo::ADC_CLOCK_MAX_HZ);
const _: () = assert!(nucleo::BAUD_ACTUAL != 0);
const _: () = assert!(error_ppm(nucleo::BAUD_ACTUAL, nucleo::BAUD) <= USART_ERROR_MAX_PPM);

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_board_spi_pin_is_fast() {
        for bus in BOARD_SPI_BUSES {
            assert_eq!(bus.check(), Ok(()), "{}", bus.device);
        }
    }

    /// A bus with a clock the checks accept, for the pin tests.
    const FAST: SpiBus = SpiBus {
        device: "test",
        apb_hz: 84_000_000,
        asked_hz: 21_000_000,
        device_max_hz: 24_000_000,
        pins: SpiPins::VERY_HIGH,
    };

    #[test]
    fn spi_clock_follows_the_hal_divider_table() {
        // stm32f4xx-hal 0.23 src/spi.rs:664-674, ratio apb / asked → divider, at each range end.
        let table = [
            (1, 2),
            (2, 2),
            (3, 4),
            (5, 4),
            (6, 8),
            (11, 8),
            (12, 16),
            (23, 16),
            (24, 32),
            (47, 32),
            (48, 64),
            (95, 64),
            (96, 128),
            (191, 128),
            (192, 256),
            (1000, 256),
        ];
        let apb = 96_000_000;
        for (ratio, div) in table {
            assert_eq!(spi_hz(apb, apb / ratio), apb / div, "ratio {ratio}");
        }
        assert_eq!(spi_hz(apb, 0), 0);
        assert_eq!(spi_hz(apb, apb + 1), 0);
    }

    #[test]
    fn board_clocks() {
        // Nucleo: 180 MHz, APB2 asked 90 MHz, APB1 by default 45 MHz (RM0390: APB1 ≤ 45 MHz).
        assert_eq!(nucleo::PCLK2_HZ, 90_000_000);
        assert_eq!(nucleo::PCLK1_HZ, 45_000_000);
        assert_eq!(nucleo::GYRO_SPI.actual_hz(), 5_625_000);
        assert_eq!(nucleo::ADC_CLOCK_HZ, 22_500_000);
        // 45 MHz / 921 600 Bd: BRR = 49 (48.83 rounded), 918 367 Bd, −0.35 %.
        assert_eq!(nucleo::BAUD_ACTUAL, 918_367);
        assert_eq!(error_ppm(nucleo::BAUD_ACTUAL, nucleo::BAUD), 3_508);
        // F405: 168 MHz, APB2 by default 84 MHz; 84 / 21 = 4 → ÷4.
        assert_eq!(f405::PCLK2_HZ, 84_000_000);
        assert_eq!(f405::IMU_SPI.actual_hz(), 21_000_000);
    }

    #[test]
    fn the_nucleo_gyro_at_8_mhz_asked_is_refused() {
        // What the board asked before: 90 / 8 = 11 → ÷8, above the L3GD20H's 10 MHz.
        let before = SpiBus {
            asked_hz: 8_000_000,
            ..nucleo::GYRO_SPI
        };
        assert_eq!(
            before.check(),
            Err(BusError::AboveDevice {
                actual_hz: 11_250_000,
                max_hz: 10_000_000
            })
        );
        let unreachable = SpiBus {
            asked_hz: 100_000_000,
            ..nucleo::GYRO_SPI
        };
        assert_eq!(unreachable.check(), Err(BusError::Unreachable));
    }

    /// The 10 MHz parts on the F405's APB2 (84 MHz): the ICM's 21 MHz bus, and 10 MHz asked
    /// (÷8 = 10.5 MHz), are both refused; 5.25 MHz (÷16) is what the table gives them.
    #[test]
    fn the_10_mhz_parts_get_their_own_f405_clock() {
        for part in [f405::LSM6DSO_SPI, crate::boards::BMI270_BUS] {
            assert_eq!(part.device_max_hz, 10_000_000, "{}", part.device);
            let on_icm_bus = SpiBus {
                asked_hz: f405::IMU_SPI.asked_hz,
                ..part
            };
            assert_eq!(
                on_icm_bus.check(),
                Err(BusError::AboveDevice {
                    actual_hz: 21_000_000,
                    max_hz: 10_000_000
                })
            );
            let asked_at_limit = SpiBus {
                asked_hz: 10_000_000,
                ..part
            };
            assert_eq!(
                asked_at_limit.check(),
                Err(BusError::AboveDevice {
                    actual_hz: 10_500_000,
                    max_hz: 10_000_000
                })
            );
            assert_eq!(part.check(), Ok(()));
            assert_eq!(part.actual_hz(), 5_250_000);
        }
    }

    #[test]
    fn a_pin_left_at_reset_speed_is_refused() {
        let bus = SpiBus {
            pins: SpiPins::AT_RESET,
            ..FAST
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
            pins: SpiPins {
                miso: PinSpeed::Medium,
                ..SpiPins::VERY_HIGH
            },
            ..FAST
        };
        assert_eq!(
            bus.check(),
            Err(BusError::PinTooSlow {
                pin: SpiPin::Miso,
                speed: PinSpeed::Medium
            })
        );
        let high = SpiBus {
            pins: SpiPins {
                sck: PinSpeed::High,
                miso: PinSpeed::High,
                mosi: PinSpeed::High,
            },
            ..FAST
        };
        assert_eq!(high.check(), Ok(()));
    }
}

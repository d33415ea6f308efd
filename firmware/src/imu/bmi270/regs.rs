//! BMI270 register addresses and values (BST-BMI270-DS000 §5; Bosch's `bmi2_defs.h` lines
//! 201–261 for the addresses, 289–290 for the configuration load status; Betaflight's
//! `accgyro_spi_bmi270.c` `bmi270Register_e` / `bmi270ConfigValues_e` for the values it writes).
//!
//! A register is a variant of [`Reg`], which knows its address; the driver's reads and writes
//! take a `Reg`. The variants are re-exported under the datasheet's names (`regs::ACC_CONF`);
//! bit fields and values stay plain consts below.

/// A BMI270 register (§5.2 register map; one flat address space, no banks). Variants are the
/// datasheet's names, so that a register is found by the name its tables give it.
#[allow(non_camel_case_types)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[repr(u8)]
pub enum Reg {
    /// CHIP_ID.
    CHIP_ID = 0x00,
    /// STATUS: drdy_acc (7), drdy_gyr (6).
    STATUS = 0x03,
    /// ACC_X_LSB (then X_MSB, Y, Z: little-endian).
    ACC_X = 0x0C,
    /// GYR_X_LSB.
    GYR_X = 0x12,
    /// SENSORTIME_0 (24 bits, 39.0625 µs per LSB).
    SENSORTIME_0 = 0x18,
    /// SENSORTIME_2.
    SENSORTIME_2 = 0x1A,
    /// INTERNAL_STATUS: message (3:0).
    INTERNAL_STATUS = 0x21,
    /// TEMPERATURE_0 (then _1): two's complement, 1/512 K per LSB, 0 at 23 °C.
    TEMPERATURE_0 = 0x22,
    /// ACC_CONF: acc_filter_perf (7), acc_bwp (6:4), acc_odr (3:0).
    ACC_CONF = 0x40,
    /// ACC_RANGE (1:0).
    ACC_RANGE = 0x41,
    /// GYR_CONF: gyr_filter_perf (7), gyr_noise_perf (6), gyr_bwp (5:4), gyr_odr (3:0).
    GYR_CONF = 0x42,
    /// GYR_RANGE: ois_range (3), gyr_range (2:0).
    GYR_RANGE = 0x43,
    /// INT1_IO_CTRL: output_en (3), od (2), lvl (1).
    INT1_IO_CTRL = 0x53,
    /// INT_MAP_DATA: drdy_int → INT1 (2).
    INT_MAP_DATA = 0x58,
    /// INIT_CTRL: 0 before the upload, 1 after it.
    INIT_CTRL = 0x59,
    /// INIT_ADDR_0: the upload's address in 16-bit words, bits 3:0.
    INIT_ADDR_0 = 0x5B,
    /// INIT_ADDR_1: bits 11:4 of it.
    INIT_ADDR_1 = 0x5C,
    /// INIT_DATA: the configuration file's bytes.
    INIT_DATA = 0x5E,
    /// PWR_CONF: fifo_self_wake_up (1), adv_power_save (0); reset value 0x03.
    PWR_CONF = 0x7C,
    /// PWR_CTRL: temp_en (3), acc_en (2), gyr_en (1), aux_en (0).
    PWR_CTRL = 0x7D,
    /// CMD.
    CMD = 0x7E,
}

pub use Reg::*;

impl Reg {
    /// The register's address (SPI address byte, bit 7 clear).
    pub const fn addr(self) -> u8 {
        self as u8
    }
}

/// The address, for the register-level model's tables.
impl From<Reg> for u8 {
    fn from(r: Reg) -> u8 {
        r as u8
    }
}

// ---- Bit fields and values ----
/// SPI read bit.
pub const READ: u8 = 0x80;
/// The BMI270's CHIP_ID.
pub const CHIP_ID_VALUE: u8 = 0x24;
/// STATUS: new accelerometer data.
pub const STATUS_DRDY_ACC: u8 = 0x80;
/// STATUS: new gyro data.
pub const STATUS_DRDY_GYR: u8 = 0x40;
/// INTERNAL_STATUS's message field.
pub const INTERNAL_STATUS_MESSAGE: u8 = 0x0F;
/// INTERNAL_STATUS message "init_ok".
pub const INTERNAL_STATUS_INIT_OK: u8 = 0x01;
/// INTERNAL_STATUS message "init_err".
pub const INTERNAL_STATUS_INIT_ERR: u8 = 0x02;
/// The temperature's "invalid" code.
pub const TEMPERATURE_INVALID: i16 = i16::MIN;
/// INT1: output enabled, push-pull, active high (Betaflight's `BMI270_VAL_INT1_IO_CTRL_PINMODE`).
pub const INT1_OUTPUT_PUSH_PULL_HIGH: u8 = 0x0A;
/// Data ready on INT1.
pub const INT_MAP_DRDY_INT1: u8 = 0x04;
/// PWR_CONF in operation: advanced power save off, FIFO self wake-up on (Betaflight's value).
pub const PWR_CONF_PERFORMANCE: u8 = 0x02;
/// Accelerometer, gyro and temperature sensor on.
pub const PWR_CTRL_ACC_GYR_TEMP: u8 = 0x0E;
/// CMD: soft reset.
pub const CMD_SOFT_RESET: u8 = 0xB6;

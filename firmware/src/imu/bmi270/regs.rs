//! BMI270 register addresses and values (BST-BMI270-DS000 §5; Bosch's `bmi2_defs.h` lines
//! 201–261 for the addresses, 289–290 for the configuration load status; Betaflight's
//! `accgyro_spi_bmi270.c` `bmi270Register_e` / `bmi270ConfigValues_e` for the values it writes).

/// SPI read bit.
pub const READ: u8 = 0x80;
/// CHIP_ID.
pub const CHIP_ID: u8 = 0x00;
/// The BMI270's CHIP_ID.
pub const CHIP_ID_VALUE: u8 = 0x24;
/// STATUS: drdy_acc (7), drdy_gyr (6).
pub const STATUS: u8 = 0x03;
/// STATUS: new accelerometer data.
pub const STATUS_DRDY_ACC: u8 = 0x80;
/// STATUS: new gyro data.
pub const STATUS_DRDY_GYR: u8 = 0x40;
/// ACC_X_LSB (then X_MSB, Y, Z: little-endian).
pub const ACC_X: u8 = 0x0C;
/// GYR_X_LSB.
pub const GYR_X: u8 = 0x12;
/// SENSORTIME_0 (24 bits, 39.0625 µs per LSB).
pub const SENSORTIME_0: u8 = 0x18;
/// SENSORTIME_2.
pub const SENSORTIME_2: u8 = 0x1A;
/// INTERNAL_STATUS: message (3:0).
pub const INTERNAL_STATUS: u8 = 0x21;
/// INTERNAL_STATUS's message field.
pub const INTERNAL_STATUS_MESSAGE: u8 = 0x0F;
/// INTERNAL_STATUS message "init_ok".
pub const INTERNAL_STATUS_INIT_OK: u8 = 0x01;
/// INTERNAL_STATUS message "init_err".
pub const INTERNAL_STATUS_INIT_ERR: u8 = 0x02;
/// TEMPERATURE_0 (then _1): two's complement, 1/512 K per LSB, 0 at 23 °C.
pub const TEMPERATURE_0: u8 = 0x22;
/// The temperature's "invalid" code.
pub const TEMPERATURE_INVALID: i16 = i16::MIN;
/// ACC_CONF: acc_filter_perf (7), acc_bwp (6:4), acc_odr (3:0).
pub const ACC_CONF: u8 = 0x40;
/// ACC_RANGE (1:0).
pub const ACC_RANGE: u8 = 0x41;
/// GYR_CONF: gyr_filter_perf (7), gyr_noise_perf (6), gyr_bwp (5:4), gyr_odr (3:0).
pub const GYR_CONF: u8 = 0x42;
/// GYR_RANGE: ois_range (3), gyr_range (2:0).
pub const GYR_RANGE: u8 = 0x43;
/// INT1_IO_CTRL: output_en (3), od (2), lvl (1).
pub const INT1_IO_CTRL: u8 = 0x53;
/// INT1: output enabled, push-pull, active high (Betaflight's `BMI270_VAL_INT1_IO_CTRL_PINMODE`).
pub const INT1_OUTPUT_PUSH_PULL_HIGH: u8 = 0x0A;
/// INT_MAP_DATA: drdy_int → INT1 (2).
pub const INT_MAP_DATA: u8 = 0x58;
/// Data ready on INT1.
pub const INT_MAP_DRDY_INT1: u8 = 0x04;
/// INIT_CTRL: 0 before the upload, 1 after it.
pub const INIT_CTRL: u8 = 0x59;
/// INIT_ADDR_0: the upload's address in 16-bit words, bits 3:0.
pub const INIT_ADDR_0: u8 = 0x5B;
/// INIT_ADDR_1: bits 11:4 of it.
pub const INIT_ADDR_1: u8 = 0x5C;
/// INIT_DATA: the configuration file's bytes.
pub const INIT_DATA: u8 = 0x5E;
/// PWR_CONF: fifo_self_wake_up (1), adv_power_save (0); reset value 0x03.
pub const PWR_CONF: u8 = 0x7C;
/// PWR_CONF in operation: advanced power save off, FIFO self wake-up on (Betaflight's value).
pub const PWR_CONF_PERFORMANCE: u8 = 0x02;
/// PWR_CTRL: temp_en (3), acc_en (2), gyr_en (1), aux_en (0).
pub const PWR_CTRL: u8 = 0x7D;
/// Accelerometer, gyro and temperature sensor on.
pub const PWR_CTRL_ACC_GYR_TEMP: u8 = 0x0E;
/// CMD.
pub const CMD: u8 = 0x7E;
/// CMD: soft reset.
pub const CMD_SOFT_RESET: u8 = 0xB6;

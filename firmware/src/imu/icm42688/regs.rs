//! ICM-42688-P register addresses and bit fields, from the datasheet (TDK InvenSense DS-000347,
//! revision 1.8): §13 "User bank 0 register map" and §14 its descriptions, §15–§16 banks 1 and 2,
//! §6 the FIFO (§6.1 packet structure, §6.2 header), §5.3 the anti-alias filter table.
//! Also shared by the register-level model (`imu::sim::icm42688`), so that model and driver read the
//! same numbers; the tests check the values the driver writes against the datasheet's tables written
//! out independently.
//!
//! A register is a variant of its bank's enum ([`Bank0`], [`Bank1`], [`Bank2`]; the part has banks
//! 0–4, the driver uses 0–2), so that the bank it needs is in its type: a step list holds
//! [`Register`]s and the driver selects each one's bank itself (REG_BANK_SEL, §14.51), and the data
//! path's plain reads and writes take a [`Bank0`], the bank selected after a reset and after every
//! step list. The variants are re-exported here under the datasheet's names (`regs::PWR_MGMT0`).

/// SPI address byte: bit 7 set for a read (§9.3 "SPI interface").
pub const READ: u8 = 0x80;

/// REG_BANK_SEL, in every bank (§14.51): the bank (0–4) the other addresses are read in. Not a
/// member of a bank's enum: the driver writes it from a register's [`Register::bank`], never by hand.
pub const REG_BANK_SEL: u8 = 0x76;

/// A register of user bank 0 (§13, §14): the bank selected after a reset and while the FIFO is
/// read, so the data path's accesses take this type alone. Variants are the datasheet's names, as
/// `embassy-net-enc28j60`'s bank enums spell them, so that a register is found by the name the
/// datasheet's tables give it.
#[allow(non_camel_case_types)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[repr(u8)]
pub enum Bank0 {
    /// DEVICE_CONFIG: bit 0 SOFT_RESET_CONFIG (§14.1); the part is ready 1 ms after it.
    DEVICE_CONFIG = 0x11,
    /// DRIVE_CONFIG (§14.2), reset value 0x05: the SPI slew rate. Left at reset by the driver; the
    /// register-level model holds its reset value.
    DRIVE_CONFIG = 0x13,
    /// INT_CONFIG: INT1_MODE (bit 2, 1 = latched), INT1_DRIVE_CIRCUIT (bit 1, 1 = push-pull),
    /// INT1_POLARITY (bit 0, 1 = active high) (§14.3).
    INT_CONFIG = 0x14,
    /// FIFO_CONFIG: FIFO_MODE in bits 7:6 (00 bypass, 01 stream, 10/11 stop-on-full) (§14.4).
    FIFO_CONFIG = 0x16,
    /// TEMP_DATA1 (high byte); then TEMP_DATA0, ACCEL_DATA_X1 .. GYRO_DATA_Z0 (§14.5–14.17), big-endian.
    TEMP_DATA1 = 0x1D,
    /// ACCEL_DATA_X1, first of the six accelerometer data registers.
    ACCEL_DATA_X1 = 0x1F,
    /// GYRO_DATA_X1, first of the six gyro data registers (§14.11), right after the accelerometer's.
    GYRO_DATA_X1 = 0x25,
    /// INT_STATUS: cleared on read (§14.19). Then FIFO_COUNTH, FIFO_COUNTL, FIFO_DATA follow it.
    INT_STATUS = 0x2D,
    /// FIFO_COUNTH (latches FIFO_COUNTL) (§14.20).
    FIFO_COUNTH = 0x2E,
    /// FIFO_DATA: a burst read pops FIFO bytes (§14.22).
    FIFO_DATA = 0x30,
    /// SIGNAL_PATH_RESET: bit 1 FIFO_FLUSH (§14.26).
    SIGNAL_PATH_RESET = 0x4B,
    /// INTF_CONFIG0 (§14.27), reset value 0x30: FIFO_HOLD_LAST_DATA_EN (7), FIFO_COUNT_REC (6: count
    /// in records), FIFO_COUNT_ENDIAN (5: big), SENSOR_DATA_ENDIAN (4: big), UI_SIFS_CFG (1:0, 11 =
    /// I²C off).
    INTF_CONFIG0 = 0x4C,
    /// INTF_CONFIG1 (§14.28), reset value 0x91: bits 7:6 hold the adaptive full-scale range (AFSR)
    /// switch, on at reset (10), which holds the gyro output for 1–2 ms when the rate crosses about
    /// ±100 °/s; RTC_MODE (2), CLKSEL (1:0).
    INTF_CONFIG1 = 0x4D,
    /// PWR_MGMT0 (§14.29): GYRO_MODE bits 3:2, ACCEL_MODE bits 1:0 (11 = low noise). After turning the
    /// gyro on, no register write for 200 µs.
    PWR_MGMT0 = 0x4E,
    /// GYRO_CONFIG0 (§14.30): GYRO_FS_SEL bits 7:5, GYRO_ODR bits 3:0. Reset 0x06.
    GYRO_CONFIG0 = 0x4F,
    /// ACCEL_CONFIG0 (§14.31): ACCEL_FS_SEL bits 7:5, ACCEL_ODR bits 3:0. Reset 0x06.
    ACCEL_CONFIG0 = 0x50,
    /// GYRO_CONFIG1 (§14.32): TEMP_FILT_BW 7:5, GYRO_UI_FILT_ORD 3:2, GYRO_DEC2_M2_ORD 1:0. Reset 0x16.
    GYRO_CONFIG1 = 0x51,
    /// GYRO_ACCEL_CONFIG0 (§14.33): ACCEL_UI_FILT_BW 7:4, GYRO_UI_FILT_BW 3:0. Reset 0x11.
    GYRO_ACCEL_CONFIG0 = 0x52,
    /// ACCEL_CONFIG1 (§14.34): ACCEL_UI_FILT_ORD 4:3, ACCEL_DEC2_M2_ORD 2:1. Reset 0x0D.
    ACCEL_CONFIG1 = 0x53,
    /// TMST_CONFIG (§14.35), reset 0x23: TMST_TO_REGS_EN (4), TMST_RES (3: 0 = 1 µs), TMST_DELTA_EN
    /// (2), TMST_FSYNC_EN (1), TMST_EN (0).
    TMST_CONFIG = 0x54,
    /// FIFO_CONFIG1 (§14.38): FIFO_RESUME_PARTIAL_RD (6), FIFO_WM_GT_TH (5), FIFO_HIRES_EN (4),
    /// FIFO_TMST_FSYNC_EN (3), FIFO_TEMP_EN (2), FIFO_GYRO_EN (1), FIFO_ACCEL_EN (0).
    FIFO_CONFIG1 = 0x5F,
    /// FIFO_CONFIG2: FIFO_WM\[7:0\]; FIFO_CONFIG3: FIFO_WM\[11:8\] (§14.39–14.40), in records with
    /// FIFO_COUNT_REC.
    FIFO_CONFIG2 = 0x60,
    /// FIFO_CONFIG3: FIFO_WM\[11:8\].
    FIFO_CONFIG3 = 0x61,
    /// FSYNC_CONFIG (§14.41), reset value 0x10: FSYNC_UI_SEL in bits 6:4 (001 at reset: the FSYNC
    /// flag tagged into the temperature's LSB; 000: FSYNC not tagged), FSYNC_UI_FLAG_CLEAR_SEL (1),
    /// FSYNC_POLARITY (0).
    FSYNC_CONFIG = 0x62,
    /// INT_CONFIG1 (§14.43), reset 0x10: INT_ASYNC_RESET (bit 4) must be cleared for proper INT1/2
    /// operation.
    INT_CONFIG1 = 0x64,
    /// INT_SOURCE0 (§14.44), reset 0x10: FIFO_THS_INT1_EN (2), FIFO_FULL_INT1_EN (1), UI_DRDY_INT1_EN (3).
    INT_SOURCE0 = 0x65,
    /// SELF_TEST_CONFIG (§14.48): ACCEL_ST_POWER (6), EN_AZ/AY/AX_ST (5:3), EN_GZ/GY/GX_ST (2:0).
    SELF_TEST_CONFIG = 0x70,
    /// WHO_AM_I (§14.50).
    WHO_AM_I = 0x75,
}

/// A register of user bank 1 (§15): the gyro's anti-alias filter and self-test codes.
#[allow(non_camel_case_types)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[repr(u8)]
pub enum Bank1 {
    /// GYRO_CONFIG_STATIC2: GYRO_AAF_DIS (1), GYRO_NF_DIS (0). Reset 0xA0.
    GYRO_CONFIG_STATIC2 = 0x0B,
    /// GYRO_CONFIG_STATIC3: GYRO_AAF_DELT 5:0.
    GYRO_CONFIG_STATIC3 = 0x0C,
    /// GYRO_CONFIG_STATIC4: GYRO_AAF_DELTSQR\[7:0\].
    GYRO_CONFIG_STATIC4 = 0x0D,
    /// GYRO_CONFIG_STATIC5: GYRO_AAF_BITSHIFT 7:4, GYRO_AAF_DELTSQR\[11:8\] 3:0.
    GYRO_CONFIG_STATIC5 = 0x0E,
    /// XG_ST_DATA, YG_ST_DATA, ZG_ST_DATA: the factory self-test codes of the gyro.
    XG_ST_DATA = 0x5F,
}

/// A register of user bank 2 (§16): the accelerometer's anti-alias filter and self-test codes.
#[allow(non_camel_case_types)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[repr(u8)]
pub enum Bank2 {
    /// ACCEL_CONFIG_STATIC2: ACCEL_AAF_DELT 6:1, ACCEL_AAF_DIS 0.
    ACCEL_CONFIG_STATIC2 = 0x03,
    /// ACCEL_CONFIG_STATIC3: ACCEL_AAF_DELTSQR\[7:0\].
    ACCEL_CONFIG_STATIC3 = 0x04,
    /// ACCEL_CONFIG_STATIC4: ACCEL_AAF_BITSHIFT 7:4, ACCEL_AAF_DELTSQR\[11:8\] 3:0.
    ACCEL_CONFIG_STATIC4 = 0x05,
    /// XA_ST_DATA, YA_ST_DATA, ZA_ST_DATA: the factory self-test codes of the accelerometer.
    XA_ST_DATA = 0x3B,
}

pub use Bank0::*;
pub use Bank1::*;
pub use Bank2::*;

/// Any register the driver configures: its bank and its address in it, as
/// `embassy-net-enc28j60`'s `Register` wraps its bank enums. A step list names registers of
/// several banks; the driver selects each one's bank from it (REG_BANK_SEL, §14.51) when it differs
/// from the bank the list selected last.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Register {
    /// User bank 0.
    Bank0(Bank0),
    /// User bank 1.
    Bank1(Bank1),
    /// User bank 2.
    Bank2(Bank2),
}

impl Register {
    /// The bank REG_BANK_SEL must hold for [`Self::addr`] to reach this register.
    pub const fn bank(self) -> u8 {
        match self {
            Register::Bank0(_) => 0,
            Register::Bank1(_) => 1,
            Register::Bank2(_) => 2,
        }
    }

    /// The address within its bank (SPI address byte, bit 7 clear).
    pub const fn addr(self) -> u8 {
        match self {
            Register::Bank0(r) => r as u8,
            Register::Bank1(r) => r as u8,
            Register::Bank2(r) => r as u8,
        }
    }
}

impl Bank0 {
    /// The address within bank 0.
    pub const fn addr(self) -> u8 {
        self as u8
    }

    /// As a [`Register`] of any bank.
    pub const fn reg(self) -> Register {
        Register::Bank0(self)
    }
}

impl From<Bank0> for Register {
    fn from(r: Bank0) -> Register {
        Register::Bank0(r)
    }
}

/// The address, for the register-level model's tables.
impl From<Bank0> for u8 {
    fn from(r: Bank0) -> u8 {
        r as u8
    }
}

impl Bank1 {
    /// The address within bank 1.
    pub const fn addr(self) -> u8 {
        self as u8
    }

    /// As a [`Register`] of any bank.
    pub const fn reg(self) -> Register {
        Register::Bank1(self)
    }
}

impl From<Bank1> for Register {
    fn from(r: Bank1) -> Register {
        Register::Bank1(r)
    }
}

/// The address, for the register-level model's tables.
impl From<Bank1> for u8 {
    fn from(r: Bank1) -> u8 {
        r as u8
    }
}

impl Bank2 {
    /// The address within bank 2.
    pub const fn addr(self) -> u8 {
        self as u8
    }

    /// As a [`Register`] of any bank.
    pub const fn reg(self) -> Register {
        Register::Bank2(self)
    }
}

impl From<Bank2> for Register {
    fn from(r: Bank2) -> Register {
        Register::Bank2(r)
    }
}

/// The address, for the register-level model's tables.
impl From<Bank2> for u8 {
    fn from(r: Bank2) -> u8 {
        r as u8
    }
}

// ---- Bit fields, by register (§14) ----
/// SOFT_RESET_CONFIG bit of DEVICE_CONFIG.
pub const SOFT_RESET: u8 = 0x01;
/// FIFO_MODE = stop-on-full: when the FIFO is full, new packets are dropped (the oldest are kept).
pub const FIFO_MODE_STOP_ON_FULL: u8 = 0b10 << 6;
/// INT_STATUS: DATA_RDY_INT.
pub const INT_DATA_RDY: u8 = 1 << 3;
/// INT_STATUS: FIFO_THS_INT (the FIFO reached its watermark).
pub const INT_FIFO_THS: u8 = 1 << 2;
/// INT_STATUS: FIFO_FULL_INT (the FIFO filled up: packets were dropped in stop-on-full mode).
pub const INT_FIFO_FULL: u8 = 1 << 1;
/// INT_STATUS: RESET_DONE_INT (set after a soft reset).
pub const INT_RESET_DONE: u8 = 1 << 4;
/// FIFO_FLUSH bit of SIGNAL_PATH_RESET.
pub const FIFO_FLUSH: u8 = 1 << 1;
/// INTF_CONFIG0: FIFO_COUNT_REC.
pub const FIFO_COUNT_REC: u8 = 1 << 6;
/// INTF_CONFIG0: FIFO_COUNT_ENDIAN (big-endian count).
pub const FIFO_COUNT_ENDIAN: u8 = 1 << 5;
/// INTF_CONFIG0: SENSOR_DATA_ENDIAN (big-endian data).
pub const SENSOR_DATA_ENDIAN: u8 = 1 << 4;
/// INTF_CONFIG0: UI_SIFS_CFG = 11, the I²C interface disabled (an SPI-only board).
pub const UI_SIFS_DISABLE_I2C: u8 = 0b11;
/// INTF_CONFIG1: the AFSR field.
pub const AFSR_MASK: u8 = 0xC0;
/// INTF_CONFIG1: AFSR off (01), as Betaflight writes it: `accgyro_spi_icm426xx.c` lines 76-78
/// (`ICM426XX_INTF_CONFIG1_AFSR_MASK 0xC0`, `..._AFSR_DISABLE 0x40`, "Fix for stalls in gyro
/// output", after ArduPilot PR 25332) and 416-420 (read, `&= ~MASK`, `|= DISABLE`, write), at
/// betaflight/betaflight commit 301d01abc4.
pub const AFSR_DISABLE: u8 = 0x40;
/// PWR_MGMT0 with both sensors in low-noise mode, temperature sensor on.
pub const PWR_LOW_NOISE: u8 = 0b1111;
/// GYRO_CONFIG1's GYRO_UI_FILT_ORD field.
pub const GYRO_UI_FILT_ORD_MASK: u8 = 0b0000_1100;
/// GYRO_UI_FILT_ORD = 10: a 3rd-order UI filter.
pub const GYRO_UI_FILT_ORD_3RD: u8 = 0b0000_1000;
/// ACCEL_CONFIG1's ACCEL_UI_FILT_ORD field.
pub const ACCEL_UI_FILT_ORD_MASK: u8 = 0b0001_1000;
/// ACCEL_UI_FILT_ORD = 10: a 3rd-order UI filter.
pub const ACCEL_UI_FILT_ORD_3RD: u8 = 0b0001_0000;
/// GYRO_ACCEL_CONFIG0's GYRO_UI_FILT_BW field.
pub const GYRO_UI_FILT_BW_MASK: u8 = 0x0F;
/// GYRO_ACCEL_CONFIG0's ACCEL_UI_FILT_BW field.
pub const ACCEL_UI_FILT_BW_MASK: u8 = 0xF0;
/// UI filter bandwidth field value 4: max(400 Hz, ODR)/10, in either field's position.
pub const UI_FILT_BW_ODR_10: u8 = 0x44;
/// PWR_MGMT0 with the gyro alone in low-noise mode.
pub const PWR_GYRO_LOW_NOISE: u8 = 0b1100;
/// PWR_MGMT0 with the accelerometer alone in low-noise mode.
pub const PWR_ACCEL_LOW_NOISE: u8 = 0b0011;
/// TMST_CONFIG: TMST_TO_REGS_EN (the time stamp readable from TMST_VALUE registers).
pub const TMST_TO_REGS_EN: u8 = 1 << 4;
/// TMST_CONFIG: TMST_RES, the time stamp's resolution: 0 = 1 µs, 1 = 16 µs (or one RTC period).
pub const TMST_RES_16US: u8 = 1 << 3;
/// TMST_CONFIG: TMST_DELTA_EN (time stamps as deltas from the previous one).
pub const TMST_DELTA_EN: u8 = 1 << 2;
/// TMST_CONFIG: TMST_FSYNC_EN (the FSYNC time stamp feature), on at reset.
pub const TMST_FSYNC_EN: u8 = 1 << 1;
/// TMST_CONFIG: TMST_EN (time stamps on), on at reset.
pub const TMST_EN: u8 = 1;
/// TMST_CONFIG's fields the driver sets (bits 7:5 are left as they read).
pub const TMST_FIELDS: u8 =
    TMST_TO_REGS_EN | TMST_RES_16US | TMST_DELTA_EN | TMST_FSYNC_EN | TMST_EN;
/// FSYNC_CONFIG: the FSYNC_UI_SEL field.
pub const FSYNC_UI_SEL_MASK: u8 = 0b0111_0000;
/// FIFO_CONFIG1: FIFO_WM_GT_TH (the watermark interrupt on every ODR while the count is above it).
pub const FIFO_WM_GT_TH: u8 = 1 << 5;
/// FIFO_CONFIG1: FIFO_HIRES_EN (20-bit packets, packet 4).
pub const FIFO_HIRES_EN: u8 = 1 << 4;
/// FIFO_CONFIG1: accel, gyro, temperature and time stamp in the FIFO (packet 3).
pub const FIFO_PACKET3_EN: u8 = 0b1111;
/// INT_CONFIG1: INT_TPULSE_DURATION (bit 6) = 1, an 8 µs interrupt pulse.
pub const INT_TPULSE_DURATION_8US: u8 = 1 << 6;
/// INT_CONFIG1: INT_TDEASSERT_DISABLE (bit 5) = 1, no minimum de-assert time.
pub const INT_TDEASSERT_DISABLE: u8 = 1 << 5;
/// INT_SOURCE0: the FIFO watermark and FIFO full on INT1.
pub const INT1_FIFO_THS_FULL: u8 = (1 << 2) | (1 << 1);
/// SELF_TEST_CONFIG: gyro self-test on all axes.
pub const ST_GYRO_ALL: u8 = 0b0000_0111;
/// SELF_TEST_CONFIG: accelerometer self-test on all axes with its power.
pub const ST_ACCEL_ALL: u8 = 0b0111_1000;
/// The ICM-42688-P's WHO_AM_I.
pub const WHO_AM_I_VALUE: u8 = 0x47;

// ---- FIFO (§6) ----
/// FIFO size, bytes (§6: 2 KiB).
pub const FIFO_BYTES: usize = 2048;
/// Header bit 7, HEADER_MSG: the FIFO is empty (the rest of the packet is not data) (§6.2).
pub const HEADER_MSG: u8 = 0x80;
/// Header of a packet 3 with an ODR time stamp: accel (6), gyro (5), timestamp 10 (3:2); bits 1:0
/// (ODR changed) are not part of the check.
pub const HEADER_PACKET3: u8 = 0b0110_1000;
/// Header of a packet 4 (20-bit): packet 3's bits and HEADER_20 (4).
pub const HEADER_PACKET4: u8 = 0b0111_1000;
/// The bits a packet's header is checked on.
pub const HEADER_CHECK_MASK: u8 = 0b1111_1100;
/// Packet 3 length (header, accel 6, gyro 6, temperature 1, time stamp 2).
pub const PACKET3_LEN: usize = 16;
/// Packet 4 length (packet 3 with a 2-byte temperature and 3 extension bytes).
pub const PACKET4_LEN: usize = 20;
/// A 16-bit sample marked invalid (§6.1: the sensor's data are not valid, e.g. while it starts).
pub const INVALID_16: i16 = i16::MIN;
/// A 20-bit sample marked invalid.
pub const INVALID_20: i32 = -524_288;

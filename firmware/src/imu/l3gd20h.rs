//! Driver of an ST L3GD20H / I3G4250D 3-axis gyro over SPI, generic over
//! `embedded_hal::spi::SpiDevice` (chip select handled by the device — on the Nucleo
//! `embedded_hal_bus::spi::ExclusiveDevice`), with typed errors.
//!
//! Register map (both parts): WHO_AM_I 0x0F (0xD7 L3GD20H, 0xD3 I3G4250D); CTRL1 0x20 (ODR, power,
//! axis enables); CTRL4 0x23 (full scale); OUT_X_L 0x28 .. OUT_Z_H 0x2D, little-endian. SPI address
//! byte: bit 7 = read, bit 6 = auto-increment. At ±2000 °/s the sensitivity is 70 m°/s per LSB.

use embedded_hal::spi::{Operation, SpiDevice};

use crate::conversion::gyro_word_from_le;
use crate::Gyro;

/// A register of the gyro (both parts' register map), which knows its address: the driver's reads
/// and writes take one, never a bare address.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[repr(u8)]
pub enum Reg {
    /// WHO_AM_I: the part's identity ([`WHO_AM_I_VALUES`]).
    WhoAmI = 0x0F,
    /// CTRL1: output data rate, bandwidth, power mode, axis enables.
    Ctrl1 = 0x20,
    /// CTRL4: block data update, full scale.
    Ctrl4 = 0x23,
    /// OUT_X_L, first of the six output registers (X, Y, Z; low byte first).
    OutXL = 0x28,
}

impl Reg {
    /// The register's address (SPI address byte, bits 7 and 6 clear).
    pub const fn addr(self) -> u8 {
        self as u8
    }
}

const READ: u8 = 0x80;
const AUTO_INC: u8 = 0x40;
/// CTRL4: BDU (bit 7), block data update: the output registers are not updated between the reads
/// of a sample's low and high bytes, so one read never mixes two samples (datasheet CTRL4 table).
const CTRL4_BDU: u8 = 0x80;
/// CTRL4: FS (bits 5:4) = 10, ±2000 °/s.
const CTRL4_FS_2000DPS: u8 = 0x20;
/// CTRL1: DR (7:6) = 11 and BW (5:4) = 11 with LOW_ODR = 0: 800 Hz, the widest bandwidth; PD (3)
/// normal mode; Zen, Yen, Xen (2:0) on.
const CTRL1_800HZ_ALL_AXES: u8 = 0xFF;
/// The output data rate the driver sets, Hz: the board samples its ADC at this rate, so that each
/// scan reads one new gyro sample (read at 1 kHz, one in five was read twice).
pub const ODR_HZ: u32 = 800;

/// Identities accepted.
pub const WHO_AM_I_VALUES: [u8; 2] = [0xD7, 0xD3];
/// rad/s per LSB at ±2000 °/s (70 m°/s).
pub const RAD_S_PER_LSB_2000DPS: f32 = 0.070 * core::f32::consts::PI / 180.0;

/// Gyro errors, generic over the SPI error.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Error<CommE> {
    /// The SPI transfer failed.
    Comm(CommE),
    /// WHO_AM_I returned this value: not a supported gyro (or nothing on the bus).
    WrongDevice(u8),
}

/// The gyro.
pub struct L3gd20<SPI> {
    spi: SPI,
}

impl<SPI: SpiDevice> L3gd20<SPI> {
    /// Checks the identity and starts the gyro: [`ODR_HZ`], all axes, ±2000 °/s, block data
    /// update.
    pub fn new(spi: SPI) -> Result<Self, Error<SPI::Error>> {
        let mut g = L3gd20 { spi };
        let id = g.read_reg(Reg::WhoAmI)?;
        if !WHO_AM_I_VALUES.contains(&id) {
            return Err(Error::WrongDevice(id));
        }
        g.write_reg(Reg::Ctrl4, CTRL4_BDU | CTRL4_FS_2000DPS)?;
        g.write_reg(Reg::Ctrl1, CTRL1_800HZ_ALL_AXES)?;
        Ok(g)
    }

    fn read_reg(&mut self, reg: Reg) -> Result<u8, Error<SPI::Error>> {
        let mut v = [0u8];
        self.spi
            .transaction(&mut [
                Operation::Write(&[reg.addr() | READ]),
                Operation::Read(&mut v),
            ])
            .map_err(Error::Comm)?;
        Ok(v[0])
    }

    fn write_reg(&mut self, reg: Reg, v: u8) -> Result<(), Error<SPI::Error>> {
        self.spi.write(&[reg.addr(), v]).map_err(Error::Comm)
    }

    /// Gives the SPI device back.
    pub fn release(self) -> SPI {
        self.spi
    }
}

impl<SPI: SpiDevice> Gyro for L3gd20<SPI> {
    type Error = Error<SPI::Error>;

    fn read_words(&mut self) -> Result<[i32; 3], Self::Error> {
        let mut b = [0u8; 6];
        self.spi
            .transaction(&mut [
                Operation::Write(&[Reg::OutXL.addr() | READ | AUTO_INC]),
                Operation::Read(&mut b),
            ])
            .map_err(Error::Comm)?;
        Ok(core::array::from_fn(|i| {
            gyro_word_from_le(b[2 * i], b[2 * i + 1])
        }))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use embedded_hal::spi::{ErrorKind, ErrorType};

    /// A register-file gyro behind a mock SPI device.
    struct Mock {
        regs: [u8; 0x40],
        fail: bool,
    }
    #[derive(Debug, PartialEq)]
    struct BusError;
    impl embedded_hal::spi::Error for BusError {
        fn kind(&self) -> ErrorKind {
            ErrorKind::Other
        }
    }
    impl ErrorType for Mock {
        type Error = BusError;
    }
    impl SpiDevice for Mock {
        fn transaction(&mut self, ops: &mut [Operation<'_, u8>]) -> Result<(), BusError> {
            if self.fail {
                return Err(BusError);
            }
            let mut addr = None;
            for op in ops {
                match op {
                    Operation::Write(w) => {
                        let a = (w[0] & 0x3F) as usize;
                        if w[0] & READ == 0 {
                            for (k, v) in w[1..].iter().enumerate() {
                                self.regs[a + k] = *v;
                            }
                        }
                        addr = Some((a, w[0] & AUTO_INC != 0));
                    }
                    Operation::Read(r) => {
                        let (a, inc) = addr.unwrap();
                        for (k, v) in r.iter_mut().enumerate() {
                            *v = self.regs[if inc { a + k } else { a }];
                        }
                    }
                    _ => unreachable!(),
                }
            }
            Ok(())
        }
    }

    #[test]
    fn configures_reads_and_scales() {
        let mut m = Mock {
            regs: [0; 0x40],
            fail: false,
        };
        m.regs[Reg::WhoAmI as usize] = 0xD7;
        let raw: [i16; 3] = [1000, -2000, i16::MAX];
        for (i, v) in raw.iter().enumerate() {
            m.regs[0x28 + 2 * i..0x2A + 2 * i].copy_from_slice(&v.to_le_bytes());
        }
        let mut g = L3gd20::new(m).unwrap();
        let words = Gyro::read_words(&mut g).unwrap();
        assert_eq!(words, raw.map(crate::conversion::gyro_word));
        // At ±2000 °/s: 70 m°/s per LSB, and a word at full scale is saturated.
        let k = crate::conversion::Scaling {
            volts_per_code: 1.0,
            rad_s_per_lsb: RAD_S_PER_LSB_2000DPS,
        };
        let s = k.convert(&[2048; 3], &words, false);
        assert!(s.saturated);
        assert!((s.rate_rad_s[0] - 70f32.to_radians()).abs() < 1e-4, "{s:?}");
        assert!((s.rate_rad_s[1] + 140f32.to_radians()).abs() < 1e-4);
        let m = g.release();
        // CTRL1: DR 11, BW 11 (800 Hz with LOW_ODR 0, the datasheet's ODR table), PD 1, Z/Y/X on.
        assert_eq!(m.regs[Reg::Ctrl1 as usize], 0b1111_1111);
        assert_eq!(ODR_HZ, 800);
        // CTRL4: BDU (bit 7) set, FS 10 (±2000 °/s).
        assert_eq!(m.regs[Reg::Ctrl4 as usize], 0b1010_0000);
    }

    #[test]
    fn typed_errors() {
        let m = Mock {
            regs: [0; 0x40],
            fail: false,
        };
        assert_eq!(L3gd20::new(m).err(), Some(Error::WrongDevice(0)));
        let m = Mock {
            regs: [0; 0x40],
            fail: true,
        };
        assert_eq!(L3gd20::new(m).err(), Some(Error::Comm(BusError)));
    }
}

//! Driver of the ARM CMSDK APB UART (QEMU mps2 boards): polled, implementing `embedded-io`.
//!
//! Registers: DATA 0x00; STATE 0x04 (bit 0 TX full, bit 1 RX full); CTRL 0x08 (bit 0 TX enable,
//! bit 1 RX enable); INTSTATUS 0x0C; BAUDDIV 0x10 (≥ 16). One byte of buffer each way.

use core::convert::Infallible;
use core::ptr::{read_volatile, write_volatile};

const DATA: usize = 0x00;
const STATE: usize = 0x04;
const CTRL: usize = 0x08;
const BAUDDIV: usize = 0x10;
const STATE_TX_FULL: u32 = 1 << 0;
const STATE_RX_FULL: u32 = 1 << 1;
const CTRL_TX_EN: u32 = 1 << 0;
const CTRL_RX_EN: u32 = 1 << 1;

/// UART0 of mps2-an386 (QEMU's first `-serial`).
pub const UART0_BASE: usize = 0x4000_4000;

/// One CMSDK UART.
pub struct CmsdkUart {
    base: usize,
}

impl CmsdkUart {
    /// Enables the UART at `base` with a baud divisor (core clock / baud, ≥ 16; QEMU ignores it).
    ///
    /// # Safety
    /// `base` must be a CMSDK UART owned by the caller alone.
    pub unsafe fn new(base: usize, bauddiv: u32) -> Self {
        let u = CmsdkUart { base };
        u.write_reg(BAUDDIV, bauddiv.max(16));
        u.write_reg(CTRL, CTRL_TX_EN | CTRL_RX_EN);
        u
    }

    fn read_reg(&self, off: usize) -> u32 {
        // SAFETY: a device register of the UART this value owns.
        unsafe { read_volatile((self.base + off) as *const u32) }
    }

    fn write_reg(&self, off: usize, v: u32) {
        // SAFETY: as above.
        unsafe { write_volatile((self.base + off) as *mut u32, v) }
    }

    /// A received byte, if one is waiting.
    pub fn try_read_byte(&mut self) -> Option<u8> {
        (self.read_reg(STATE) & STATE_RX_FULL != 0).then(|| self.read_reg(DATA) as u8)
    }

    /// Sends a byte if the transmitter has room.
    pub fn try_write_byte(&mut self, b: u8) -> bool {
        if self.read_reg(STATE) & STATE_TX_FULL != 0 {
            return false;
        }
        self.write_reg(DATA, u32::from(b));
        true
    }
}

impl embedded_io::ErrorType for CmsdkUart {
    type Error = Infallible;
}

impl embedded_io::ReadReady for CmsdkUart {
    fn read_ready(&mut self) -> Result<bool, Infallible> {
        Ok(self.read_reg(STATE) & STATE_RX_FULL != 0)
    }
}

impl embedded_io::WriteReady for CmsdkUart {
    fn write_ready(&mut self) -> Result<bool, Infallible> {
        Ok(self.read_reg(STATE) & STATE_TX_FULL == 0)
    }
}

impl embedded_io::Read for CmsdkUart {
    /// Blocks until at least one byte is available (as `embedded-io` requires), then returns what
    /// is there without waiting further.
    fn read(&mut self, buf: &mut [u8]) -> Result<usize, Infallible> {
        if buf.is_empty() {
            return Ok(0);
        }
        let mut n = 0;
        while n < buf.len() {
            match self.try_read_byte() {
                Some(b) => {
                    buf[n] = b;
                    n += 1;
                }
                None if n > 0 => break,
                None => core::hint::spin_loop(),
            }
        }
        Ok(n)
    }
}

impl embedded_io::Write for CmsdkUart {
    /// Blocks until at least one byte is accepted, then writes what fits without waiting further.
    fn write(&mut self, buf: &[u8]) -> Result<usize, Infallible> {
        let mut n = 0;
        while n < buf.len() {
            if self.try_write_byte(buf[n]) {
                n += 1;
            } else if n > 0 {
                break;
            } else {
                core::hint::spin_loop();
            }
        }
        Ok(n)
    }

    fn flush(&mut self) -> Result<(), Infallible> {
        while self.read_reg(STATE) & STATE_TX_FULL != 0 {
            core::hint::spin_loop();
        }
        Ok(())
    }
}

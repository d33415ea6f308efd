//! [`Transport`] over a serial port (a board's UART bridge, or the pty of the firmware in QEMU).

use super::client::{LinkError, Transport};
use std::io::{Read, Write};
use std::time::Duration;

/// Default baud rate: the firmware's UART runs at 921 600 Bd (no effect on a pty).
pub const DEFAULT_BAUD: u32 = 921_600;

/// An open serial port.
pub struct SerialTransport {
    port: Box<dyn serialport::SerialPort>,
    name: String,
}

impl SerialTransport {
    /// Opens `path` at `baud`.
    pub fn open(path: &str, baud: u32) -> Result<SerialTransport, LinkError> {
        let port = serialport::new(path, baud)
            .timeout(Duration::from_millis(50))
            .open()
            .map_err(|e| {
                LinkError::Io(
                    format!("cannot open serial port {path} (is the board plugged in, and do you have permission? try `ls -l {path}`)"),
                    std::io::Error::other(e),
                )
            })?;
        Ok(SerialTransport {
            port,
            name: path.to_string(),
        })
    }
}

impl Transport for SerialTransport {
    fn send(&mut self, bytes: &[u8]) -> Result<(), LinkError> {
        self.port
            .write_all(bytes)
            .and_then(|_| self.port.flush())
            .map_err(|e| LinkError::Io(format!("writing to {}", self.name), e))
    }

    fn receive(&mut self, buf: &mut [u8], timeout: Duration) -> Result<usize, LinkError> {
        self.port
            .set_timeout(timeout.max(Duration::from_millis(1)))
            .map_err(|e| {
                LinkError::Io(
                    format!("configuring {}", self.name),
                    std::io::Error::other(e),
                )
            })?;
        match self.port.read(buf) {
            Ok(n) => Ok(n),
            Err(e)
                if e.kind() == std::io::ErrorKind::TimedOut
                    || e.kind() == std::io::ErrorKind::WouldBlock =>
            {
                Ok(0)
            }
            Err(e) => Err(LinkError::Io(format!("reading from {}", self.name), e)),
        }
    }
}

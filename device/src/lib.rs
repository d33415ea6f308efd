//! The link to a device: the protocol client ([`client`]), the transports it runs over (a serial port,
//! [`serial`], or the in-process simulated device, [`sim`], perhaps held by the simulated hand of
//! [`sim_hand`]), and the live calibration procedure
//! ([`procedure`]) with its operator prompts ([`operator`]), the instruction and live checks of each
//! segment (`live_check`), the verification of the stored calibration ([`verify`]), hand-held
//! mode ([`handheld`]; its every window logged by `window_log` and calibrated as `host segment`
//! would by [`hand_session`]), the first checks of a freshly flashed board ([`bringup`], with the device's health report in
//! `bringup_health` and the poses and waving of `bringup_motion`), and the operator's live page
//! ([`view`]).

#![deny(missing_docs)]

pub mod bringup;
mod bringup_health;
pub mod bringup_motion;
pub mod client;
pub mod hand_session;
pub mod handheld;
pub(crate) mod live_check;
pub mod operator;
pub mod procedure;
pub mod serial;
pub mod sim;
pub mod sim_hand;
pub mod verify;
pub mod view;
pub(crate) mod window_log;

pub use client::{DeviceClient, LinkError, Transport};

use serial::SerialTransport;
use sim::SimDevice;
use std::time::Duration;

/// Either kind of device link.
pub enum AnyTransport {
    /// The in-process simulated device.
    Sim(Box<SimDevice>),
    /// A serial port or pty.
    Serial(SerialTransport),
}

impl Transport for AnyTransport {
    fn send(&mut self, bytes: &[u8]) -> Result<(), LinkError> {
        match self {
            AnyTransport::Sim(d) => d.send(bytes),
            AnyTransport::Serial(s) => s.send(bytes),
        }
    }
    fn receive(&mut self, buf: &mut [u8], timeout: Duration) -> Result<usize, LinkError> {
        match self {
            AnyTransport::Sim(d) => d.receive(buf, timeout),
            AnyTransport::Serial(s) => s.receive(buf, timeout),
        }
    }
}

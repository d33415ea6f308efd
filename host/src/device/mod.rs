//! The link to a device: the protocol client, and the transports it runs over (a serial port, or the
//! in-process simulated device).

pub mod client;
pub mod handheld;
pub mod procedure;
pub mod serial;
pub mod sim;

pub use client::{DeviceClient, LinkError, Transport};

//! A UART link whose receiver is drained by an interrupt: the receive interrupt (highest priority,
//! a few instructions) moves each byte into a single-producer single-consumer queue, and the link
//! service at the lowest priority reads the queue and writes the transmitter when it has room.
//!
//! Why: at 921 600 Bd a byte arrives every 10.9 µs and the USART holds one; a link service that polls
//! the data register from the lowest priority loses bytes whenever the sampling task runs longer than
//! that. The queue absorbs a burst of [`RX_QUEUE`] bytes — more than a whole host frame — and a
//! byte that finds it full is counted ([`RxQueueLink::overflows`]); the frame it breaks is answered
//! as malformed by the protocol, never fatal.

use core::sync::atomic::{AtomicU32, Ordering};

use heapless::spsc::{Consumer, Producer};

use crate::ByteLink;

/// Receive queue length, bytes (a host frame is at most `shared::wire::HOST_FRAME_MAX`).
pub const RX_QUEUE: usize = 256;

/// Bytes lost because the receive queue was full, since boot (written by the receive interrupt).
pub static RX_OVERFLOWS: AtomicU32 = AtomicU32::new(0);

/// The receive interrupt's half: hands one received byte to the queue.
#[inline]
pub fn on_rx_byte(producer: &mut Producer<'_, u8>, byte: u8) {
    if producer.enqueue(byte).is_err() {
        RX_OVERFLOWS.fetch_add(1, Ordering::Relaxed);
    }
}

/// The link service's half: the queue's consumer and an `embedded-hal-nb` transmitter.
pub struct RxQueueLink<'q, TX> {
    rx: Consumer<'q, u8>,
    tx: TX,
}

impl<'q, TX> RxQueueLink<'q, TX> {
    /// Around the queue's consumer and the transmitter.
    pub fn new(rx: Consumer<'q, u8>, tx: TX) -> Self {
        RxQueueLink { rx, tx }
    }

    /// Bytes lost to a full receive queue since boot.
    pub fn overflows(&self) -> u32 {
        RX_OVERFLOWS.load(Ordering::Relaxed)
    }
}

impl<TX: embedded_hal_nb::serial::Write<u8>> ByteLink for RxQueueLink<'_, TX> {
    fn try_read(&mut self) -> Option<u8> {
        self.rx.dequeue()
    }

    fn try_write(&mut self, byte: u8) -> bool {
        self.tx.write(byte).is_ok()
    }
}

/// Outgoing bytes staged up to one packet and handed to a packet writer in one piece (a USB class's
/// `write`): one 64-byte packet rather than 64 one-byte packets. Order is kept and nothing is lost:
/// a byte that finds the stage full after a flush is refused, and the link service retries it.
pub struct PacketStager<const N: usize> {
    buf: [u8; N],
    len: usize,
}

impl<const N: usize> Default for PacketStager<N> {
    fn default() -> Self {
        Self::new()
    }
}

impl<const N: usize> PacketStager<N> {
    /// Empty.
    pub const fn new() -> Self {
        PacketStager {
            buf: [0; N],
            len: 0,
        }
    }

    /// Nothing staged.
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// Stages one byte, first flushing a full stage through `write` (which returns how many of the
    /// bytes it took, from the front). False when the stage stays full.
    pub fn push(&mut self, byte: u8, write: impl FnMut(&[u8]) -> usize) -> bool {
        if self.len == N {
            self.flush(write);
            if self.len == N {
                return false;
            }
        }
        self.buf[self.len] = byte;
        self.len += 1;
        true
    }

    /// Hands the staged bytes to `write`; what it does not take stays staged, in order.
    pub fn flush(&mut self, mut write: impl FnMut(&[u8]) -> usize) {
        if self.len == 0 {
            return;
        }
        let taken = write(&self.buf[..self.len]).min(self.len);
        self.buf.copy_within(taken..self.len, 0);
        self.len -= taken;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use heapless::spsc::Queue;

    /// A transmitter that takes `room` bytes, then refuses.
    struct Tx {
        sent: heapless::Vec<u8, 8>,
        room: usize,
    }
    impl embedded_hal_nb::serial::ErrorType for Tx {
        type Error = core::convert::Infallible;
    }
    impl embedded_hal_nb::serial::Write<u8> for Tx {
        fn write(&mut self, b: u8) -> embedded_hal_nb::nb::Result<(), Self::Error> {
            if self.sent.len() >= self.room {
                return Err(embedded_hal_nb::nb::Error::WouldBlock);
            }
            self.sent
                .push(b)
                .map_err(|_| embedded_hal_nb::nb::Error::WouldBlock)
        }
        fn flush(&mut self) -> embedded_hal_nb::nb::Result<(), Self::Error> {
            Ok(())
        }
    }

    #[test]
    fn bytes_in_order_overflow_counted_and_tx_backpressure() {
        let mut q: Queue<u8, 4> = Queue::new();
        let (mut p, c) = q.split();
        let before = RX_OVERFLOWS.load(Ordering::Relaxed);
        let capacity = 3; // heapless 0.9: a Queue<_, N> holds N - 1
        for b in 1..=capacity as u8 + 2 {
            on_rx_byte(&mut p, b);
        }
        let mut link = RxQueueLink::new(
            c,
            Tx {
                sent: heapless::Vec::new(),
                room: 2,
            },
        );
        assert!(link.overflows() >= before + 2);
        let got: heapless::Vec<u8, 8> = core::iter::from_fn(|| link.try_read()).collect();
        assert_eq!(&got[..], &[1, 2, 3]);
        assert!(link.try_write(7) && link.try_write(8));
        assert!(
            !link.try_write(9),
            "a full transmitter refuses, the caller retries"
        );
        assert_eq!(&link.tx.sent[..], &[7, 8]);
    }

    #[test]
    fn stager_keeps_order_loses_nothing_and_refuses_when_the_writer_does() {
        // A writer that takes at most 3 bytes per call, and nothing while `closed`.
        let mut sent: Vec<u8> = Vec::new();
        let mut closed = false;
        let mut st = PacketStager::<4>::new();
        let mut accepted = Vec::new();
        for b in 0..20u8 {
            if b == 10 {
                closed = true;
            }
            let ok = st.push(b, |bytes| {
                if closed {
                    return 0;
                }
                let n = bytes.len().min(3);
                sent.extend_from_slice(&bytes[..n]);
                n
            });
            if ok {
                accepted.push(b);
            }
            if b == 14 {
                closed = false;
            }
        }
        assert!(
            accepted.len() < 20,
            "a full stage with a closed writer refuses"
        );
        while !st.is_empty() {
            st.flush(|bytes| {
                sent.extend_from_slice(bytes);
                bytes.len()
            });
        }
        assert_eq!(sent, accepted, "every accepted byte sent once, in order");
    }
}

//! Register-level models of the IMUs (in progress).

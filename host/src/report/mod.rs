//! What a person reads: the terminal text of a calibration ([`text`]), the HTML/Markdown report with
//! its figures and the navigation replay ([`document`], [`plot`], [`navigation`]), and two
//! calibrations side by side ([`compare`]).

pub mod compare;
pub mod document;
pub mod navigation;
pub mod plot;
pub mod text;
pub mod thermal;

pub use text::{render, render_prediction};

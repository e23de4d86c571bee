//! SVG figures drawn with plotters into strings. This file holds what every
//! figure shares (the frame, the legend, axes and colours) and the figures
//! of the correlation and the iteration: error versus frequency, error per
//! channel, misfit and parameter values per iteration. The FRF overlays are
//! in [`frf`], the frequency and phase axes in [`axes`], the structure and
//! its mode shapes in [`structure`], the MAC matrix and the stabilisation
//! diagram in [`modes`], the misfit of each step of the loop in [`steps`].
//!
//! Text is emitted as SVG `<text>` elements in a generic `sans-serif` family
//! (plotters is built without its font features), so the figures need no
//! font files and the browser's own font renders them. Legends are drawn as
//! a row under the title rather than inside the axes, where they would hide
//! curves.
//!
//! What every figure shares has a file each: [`style`] (colours and line
//! styles), [`frame`](mod@frame) (the SVG backend, title and legend), [`axes`] (log
//! axes, ticks, the frequency axis and the continuous phase); the figures
//! of the correlation are in [`correlation`], those of the iteration in
//! [`history`]. Curves with more points than pixel columns are thinned to
//! the points that draw them ([`decimate`]).

// `::frf` is the crate; `frf` alone is the overlay module below
use ::frf::C64;

pub(crate) mod axes;
mod correlation;
mod decimate;
mod frame;
pub(crate) mod frf;
mod history;
pub(crate) mod modes;
mod projection;
mod steps;
pub(crate) mod structure;
mod style;

// what the figures share, nameable as `super::...` in every figure's file
use axes::*;
use frame::*;
use style::*;

pub(crate) use correlation::{ChannelSeries, ErrorCurve, channel_errors, error_vs_frequency};
pub(crate) use frame::{LegendEntry, Mark, PlotError};
pub(crate) use history::{ParameterTrace, convergence, parameter_history};
pub(crate) use steps::misfit_steps;
pub(crate) use style::{INITIAL, MEASURED, MEASURED_FRF, UPDATED};

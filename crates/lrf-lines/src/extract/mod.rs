//! Line extraction from one laser scan: split-and-merge over the scan's points, a
//! weighted least-squares fit with an honest 2×2 covariance per line, and merging of
//! adjacent collinear lines by a chi-square test (docs/ARCHITECTURE.md §3).
//!
//! The pipeline, one private module per step: `points` (beams → points indexed by beam,
//! runs of valid ones cut at invalid beams and at gaps `breakpoint` finds too wide) → `split` (iterative end-point fit)
//! → `fit` (weighted fit with end trimming, Pfister et al. 2003) → `merge` (collinear
//! merging); each step passes beam ranges to the next. `extractor` drives them with
//! reusable buffers, so steady-state extraction does not allocate. The public
//! surface is [`LineExtractor`], [`ExtractionParams`] and [`ExtractionError`].

mod breakpoint;
mod error;
mod extractor;
mod fit;
mod merge;
mod moments;
mod params;
mod points;
mod range_noise;
mod split;

pub use error::ExtractionError;
pub use extractor::{LineExtractor, SPLIT_SIGMAS};
pub use params::ExtractionParams;

//! Sorts on the GPU: the generic radix sort of (key, value) pairs ([`radix`], with its bitonic
//! baseline; in one dispatch a pass on NVIDIA, [`onesweep`]) and, built on it, the depth sort of
//! an effect with `sort: true` ([`depth`]: depth keys along the camera, quantised to 16 bits
//! over the live range found by [`quantise`]). The flocking grid's counting sort reuses the
//! radix sort's scan; [`words`] sorts and scans words from the CPU.
//!
//! Imports only [`crate::device`].

pub(crate) mod depth;
pub(crate) mod onesweep;
pub(crate) mod program;
pub(crate) mod quantise;
pub(crate) mod radix;
#[cfg(feature = "tools")]
pub(crate) mod words;

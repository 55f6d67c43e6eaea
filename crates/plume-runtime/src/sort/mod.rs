//! Sorts on the GPU: the generic radix sort of (key, value) pairs ([`radix`], with its bitonic
//! baseline) and, built on it, the depth sort of an effect with `sort: true` ([`depth`]: depth
//! keys along the camera, quantised to 16 bits by [`quantise`]). The flocking grid's counting
//! sort and the events' ordering reuse the radix sort's scan and passes.
//!
//! Imports only [`crate::device`].

pub(crate) mod depth;
pub(crate) mod quantise;
pub(crate) mod radix;
pub(crate) mod words;

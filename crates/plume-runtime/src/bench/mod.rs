//! Benchmarks and measurements, for `plume bench`, `plume accuracy` and the tools in
//! `examples/`: the update against a copy kernel, the draw, the events' cost, the radix sort
//! alone, the integrators' error against time per step (and its SVG plot), and the GPU pass timer they share.
//!
//! Imports every other folder; nothing imports it.

pub(crate) mod accuracy;
pub(crate) mod graph;
pub(crate) mod plot;
pub(crate) mod sort;
pub(crate) mod timer;
pub(crate) mod update;

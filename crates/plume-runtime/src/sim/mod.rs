//! Simulation and events: what advances an effect by steps. [`steps`] records a group's
//! kernels (spawn, update, a field's bake; or a stateless group's bookkeeping), [`flock`] the
//! flocking pass between spawn and update, [`group`] holds one group's state (its resources,
//! kernels, depth sort and spawn schedule) and steps, reads and times it, and [`events`] orders
//! an event stream's firings for the child group, [`scene_depth`] binds the host's depth image
//! for a `SceneDepth` collider, [`graph`] steps several groups and their
//! streams together, [`reports`] gathers reported events' firings for the host, and [`effect`] is the public [`effect::Effect`]: one group, or a graph
//! ([`effect_read`]: what it tells its host).
//!
//! Imports [`crate::device`] and [`crate::sort`]; never the draw.

pub(crate) mod batch;
pub(crate) mod bounds;
pub(crate) mod counts;
pub(crate) mod effect;
pub(crate) mod effect_read;
pub(crate) mod events;
pub(crate) mod flock;
pub(crate) mod graph;
pub(crate) mod group;
pub(crate) mod planned;
pub(crate) mod reports;
pub(crate) mod scene_depth;
pub(crate) mod steps;
pub(crate) mod watch;

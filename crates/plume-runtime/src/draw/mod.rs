//! Drawing particles straight from the GPU buffers. The public [`renderer::EffectRenderer`]
//! (every group's draw, made and prepared by `Effect` methods defined there) is built of one
//! raster draw per group ([`raster`]: the group's generated draw module on a render pipeline,
//! recorded into the caller's render pass, its [`instances`] every slot, the compacted
//! [`live_list`] of live slots or the live count),
//! after the frame's preparation ([`frame`]: the depth sort along the camera, and the draw
//! order it gives); the ribbons drawn before it ([`trail`]), the sprite
//! texture ([`texture`]), a lit draw's lights ([`lights`]), the scene depth a soft draw reads ([`scene_depth`]), and what they
//! share ([`pipeline`], [`target`], [`camera`]); then the two image-only ways of drawing that
//! `plume render` uses: the compute renderer ([`splat`]) and the bloom of a glowing effect
//! ([`glow`]).
//!
//! Imports [`crate::device`], [`crate::sort`] and [`crate::sim`]; nothing above.

pub(crate) mod camera;
pub(crate) mod frame;
pub(crate) mod glow;
pub(crate) mod instances;
pub(crate) mod lights;
pub(crate) mod live_list;
pub(crate) mod particle_light;
pub(crate) mod pipeline;
pub(crate) mod raster;
pub(crate) mod renderer;
pub(crate) mod scene_depth;
pub(crate) mod splat;
pub(crate) mod target;
pub(crate) mod texture;
pub(crate) mod trail;

//! What every kernel shares: the workgroup width, the thread index of a 2D dispatch, and where
//! a particle's 16-byte words lie in a word-major buffer. Features and stages both emit
//! kernels, so these sit at the bottom with the writer.

use crate::base::writer::Writer;

/// Threads per workgroup of `spawn` and `update`.
pub const WORKGROUP: u32 = 256;

/// Emits the index of this thread in a 2D dispatch of WORKGROUP-wide groups (`let {var} = ...`;
/// 2D because one dimension holds at most 65,535 groups), and a return for threads at or past
/// `bound` when one is given. Every kernel takes `gid` and `groups` builtins for it.
pub(crate) fn emit_thread_index(w: &mut Writer, var: &str, bound: Option<&str>) {
    w.line(format!("let {var} = gid.x + gid.y * groups.x * WORKGROUP;"));
    if let Some(bound) = bound {
        w.block(format!("if ({var} >= {bound})"), |w| w.line("return;"));
    }
}

/// The index, in a buffer of `slots` particles, of 16-byte word `k` of local slot `i`. The
/// state is stored **word-major**: word k of every slot of a buffer, then word k + 1 (a
/// buffer's words are `slots` `vec4<u32>` per struct word). A thread that loads its own
/// particle's words then reads, across a warp, 512 contiguous bytes per load, as a copy kernel
/// does, with no exchange through workgroup memory and no barrier; particle-major words
/// (slot i's at i · VEC4S + k) left every load half-coalesced, and staging them through
/// workgroup memory cost the barriers (docs/performance.md, "The update at large sizes").
pub fn word_index(k: u32, i: &str, slots: &str) -> String {
    match k {
        0 => i.to_string(),
        1 => format!("{slots} + {i}"),
        _ => format!("{k}u * {slots} + {i}"),
    }
}

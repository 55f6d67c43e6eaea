//! The checks of `render.texture` as a file writes it (the PNG itself is read, and its errors
//! located, by [`super::TextureIr::load`]'s callers).

use super::{Play, Texture};
use crate::base::check::Checker;
use crate::base::path::ValuePath;

impl Texture {
    /// Checks that each image names a file, that the flipbook has at least one column and one
    /// row, that a rate is > 0, and that `random_start` goes with a rate; `path` names
    /// `render.texture`.
    pub(crate) fn check(&self, path: &ValuePath, c: &mut Checker) {
        const NO_FILE: &str = "names no file; give a PNG's path relative to the effect file";
        if self.file.trim().is_empty() {
            c.error(&path.field("file"), NO_FILE);
        }
        if self
            .second
            .as_ref()
            .is_some_and(|s| s.file.trim().is_empty())
        {
            c.error(&path.field("second").field("file"), NO_FILE);
        }
        let frames = path.field("frames");
        for (i, (name, n)) in [("columns", self.frames.0), ("rows", self.frames.1)]
            .into_iter()
            .enumerate()
        {
            if n == 0 {
                c.error(&frames.component(i, name), "must be at least 1");
            }
        }
        match self.play {
            Play::Rate(fps) => {
                c.positive(&path.field("play").variant("Rate").inner(), fps);
            }
            Play::OverLife if self.random_start => c.error(
                &path.field("random_start"),
                "applies to frames played at a rate (play: Rate(fps)); a flipbook played over life starts at frame 0",
            ),
            Play::OverLife => {}
        }
    }
}

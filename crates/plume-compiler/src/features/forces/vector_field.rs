//! Imported vector fields: `VectorField(file: "wind.fga", strength: 2.0, ..)`, an acceleration
//! sampled from a 3D grid of vectors in the FGA format, the plain-text format that Unreal's and
//! Unity's vector-field tools write: the sample counts (nx, ny, nz), the box's min and max
//! corners, then nx·ny·nz vectors, x fastest, then y, then z; numbers separated by commas or
//! white space.
//!
//! Node (i, j, k) sits at min + (max − min) · (i/(nx−1), j/(ny−1), k/(nz−1)): the grid's corners
//! are the box's. Between nodes the field is trilinear. The effect places the box with `offset`
//! and `scale` (the field's point p is the world's offset + scale · p), and says what happens
//! outside it: `Clamp` (the border's values extend), `Tile` (the field repeats; it is
//! continuous where its first and last nodes agree) or `Zero`. a = strength · sample.
//!
//! The file is read once, at compile time (`read_vector_fields`); its samples reach the GPU
//! in the `force_data` storage binding as f32 (12 bytes a node), and the f64 reference
//! ([`VectorFieldTerm::sample`]) interpolates the very same f32 values. One vector field per
//! effect.

use std::path::{Path, PathBuf};
use std::sync::Arc;

use glam::DVec3;
use serde::Deserialize;

use super::{Force, ForceTerm, Stiffness};
use crate::base::check::Checker;
use crate::base::path::ValuePath;
use crate::base::values::Vec3;
use crate::base::writer::{f32_lit, vec3_lit, Writer};

/// Field names, as written in effect files.
pub(crate) const FIELDS: &[&str] = &["file", "strength", "offset", "scale", "outside"];

/// The most nodes a vector field may have (2²², 48 MiB of f32 on the GPU).
pub(crate) const MAX_NODES: u64 = 1 << 22;

/// The largest FGA file read (a text line a node, well under 64 bytes each).
pub(crate) const MAX_FILE_BYTES: u64 = 256 << 20;

/// What the field is outside its box.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize)]
pub enum Outside {
    /// The border's values extend outward.
    #[default]
    Clamp,
    /// The field repeats with the box's size as its period.
    Tile,
    /// No acceleration outside.
    Zero,
}

/// A vector field as written in an effect file.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct VectorField {
    /// The FGA file, relative to the effect file.
    pub file: String,
    /// Multiplies every sample (the samples are accelerations in m/s² at strength 1).
    #[serde(default = "one")]
    pub strength: f64,
    /// Where the field's origin sits in the world (m).
    #[serde(default = "origin")]
    pub offset: Vec3,
    /// The field's size against the world's (> 0): the box spans offset + scale · [min, max].
    #[serde(default = "one")]
    pub scale: f64,
    /// What the field is outside its box.
    #[serde(default)]
    pub outside: Outside,
    /// The file's grid, read by `read_vector_fields` before the checks.
    #[serde(skip)]
    pub grid: Option<Arc<Grid>>,
}

fn one() -> f64 {
    1.0
}

fn origin() -> Vec3 {
    Vec3(0.0, 0.0, 0.0)
}

/// An FGA file's grid: counts, box and samples (f32, as the GPU holds them).
#[derive(Clone, Debug, PartialEq)]
pub struct Grid {
    /// Nodes along x, y and z (each >= 2).
    pub counts: [u32; 3],
    /// The box's first corner, node (0, 0, 0).
    pub min: DVec3,
    /// The box's last corner.
    pub max: DVec3,
    /// The vectors, x fastest, then y, then z.
    pub samples: Vec<[f32; 3]>,
}

/// Parses FGA text into a grid, or says what is wrong with it (which number, where).
pub(crate) fn parse_fga(text: &str) -> Result<Grid, String> {
    let mut numbers = text
        .split(|c: char| c == ',' || c.is_whitespace())
        .filter(|s| !s.is_empty())
        .enumerate();
    let mut next = |what: &str| -> Result<f64, String> {
        let (k, word) = numbers
            .next()
            .ok_or_else(|| format!("the file ends before its {what}"))?;
        let value: f64 = word
            .parse()
            .map_err(|_| format!("number {} ({what}) is `{word}`, not a number", k + 1))?;
        if !value.is_finite() {
            return Err(format!(
                "number {} ({what}) is {value}: every value must be finite",
                k + 1
            ));
        }
        Ok(value)
    };
    let mut counts = [0u32; 3];
    for (axis, count) in ["x", "y", "z"].iter().zip(&mut counts) {
        let n = next(&format!("node count along {axis}"))?;
        if n.fract() != 0.0 || !(2.0..=f64::from(u32::MAX)).contains(&n) {
            return Err(format!(
                "the node count along {axis} is {n}: a vector field needs a whole count of at least 2 on every axis"
            ));
        }
        *count = n as u32;
    }
    let nodes = counts.iter().map(|&n| u64::from(n)).product::<u64>();
    if nodes > MAX_NODES {
        return Err(format!(
            "{} x {} x {} = {nodes} nodes is more than the {MAX_NODES} a vector field may have",
            counts[0], counts[1], counts[2]
        ));
    }
    let mut corner = |name: &str| -> Result<DVec3, String> {
        Ok(DVec3::new(
            next(&format!("{name}.x"))?,
            next(&format!("{name}.y"))?,
            next(&format!("{name}.z"))?,
        ))
    };
    let (min, max) = (corner("min")?, corner("max")?);
    if !min.cmplt(max).all() {
        return Err(format!(
            "the box's min {min} must be below its max {max} on every axis"
        ));
    }
    let mut samples = Vec::with_capacity(nodes as usize);
    for node in 0..nodes {
        let what = format!("vector of node {node}");
        samples.push([
            next(&what)? as f32,
            next(&what)? as f32,
            next(&what)? as f32,
        ]);
    }
    if let Some((k, word)) = numbers.next() {
        return Err(format!(
            "number {} (`{word}`) is one too many: {} nodes take {} numbers after the header",
            k + 1,
            nodes,
            3 * nodes
        ));
    }
    Ok(Grid {
        counts,
        min,
        max,
        samples,
    })
}

/// Reads every vector field's file (relative to `base_dir`) into its grid, recording what is
/// wrong, located at the force's `file`, in `c`.
pub(crate) fn read_vector_fields(forces: &mut [Force], base_dir: Option<&Path>, c: &mut Checker) {
    for (i, force) in forces.iter_mut().enumerate() {
        let path = super::force_path(i, force).field("file");
        let Force::VectorField(field) = force else {
            continue;
        };
        match read_file(&field.file, base_dir) {
            Ok(grid) => field.grid = Some(Arc::new(grid)),
            Err(message) => c.error(&path, message),
        }
    }
}

fn read_file(file: &str, base_dir: Option<&Path>) -> Result<Grid, String> {
    let path = base_dir.map_or_else(|| PathBuf::from(file), |dir| dir.join(file));
    let shown = path.display();
    use crate::base::files::ReadError;
    let bytes = crate::base::files::read(&path, MAX_FILE_BYTES).map_err(|e| match e {
        ReadError::Open(e) => format!("cannot open vector field `{shown}`: {e}"),
        ReadError::Read(e) => format!("cannot read vector field `{shown}`: {e}"),
        ReadError::TooLarge(size) => format!(
            "vector field `{shown}` is {size} bytes, more than the {MAX_FILE_BYTES} read: resample it coarser"
        ),
    })?;
    let text = String::from_utf8(bytes)
        .map_err(|e| format!("cannot read vector field `{shown}`: not UTF-8 text ({e})"))?;
    parse_fga(&text).map_err(|why| format!("vector field `{shown}`: {why}"))
}

impl VectorField {
    /// Checks the placement and strength (the file was checked as it was read).
    pub(crate) fn check(&self, path: &ValuePath, c: &mut Checker) {
        c.finite(&path.field("strength"), self.strength);
        c.vec3(&path.field("offset"), self.offset);
        c.positive(&path.field("scale"), self.scale);
    }

    /// Lowers to a term (after `read_vector_fields` gave it its grid; None otherwise, which
    /// the read recorded as an error).
    pub(crate) fn lower(&self, origin: usize) -> Option<VectorFieldTerm> {
        Some(VectorFieldTerm {
            grid: self.grid.clone()?,
            strength: self.strength,
            offset: self.offset.d(),
            scale: self.scale,
            outside: self.outside,
            origins: vec![origin],
        })
    }
}

/// A vector field in the IR.
#[derive(Clone, Debug, PartialEq)]
pub struct VectorFieldTerm {
    /// The samples.
    pub grid: Arc<Grid>,
    /// Their multiplier.
    pub strength: f64,
    /// The field's origin in the world (m).
    pub offset: DVec3,
    /// The field's size against the world's.
    pub scale: f64,
    /// Outside the box.
    pub outside: Outside,
    /// Source forces.
    pub origins: Vec<usize>,
}

impl VectorFieldTerm {
    /// The samples as the `force_data` binding holds them: x, y, z of each node in order.
    pub fn data(&self) -> Vec<f32> {
        self.grid.samples.iter().flatten().copied().collect()
    }

    /// Where world point `x` falls in node units (0 to n − 1 on each axis inside the box),
    /// with `outside` applied; None where the field is zero there.
    fn node_coordinates(&self, x: DVec3) -> Option<DVec3> {
        let g = &self.grid;
        let last = DVec3::from_array(g.counts.map(|n| f64::from(n - 1)));
        let rel = ((x - self.offset) / self.scale - g.min) / (g.max - g.min);
        match self.outside {
            Outside::Clamp => Some(rel.clamp(DVec3::ZERO, DVec3::ONE) * last),
            Outside::Tile => Some((rel - rel.floor()) * last),
            Outside::Zero => {
                (rel.cmpge(DVec3::ZERO).all() && rel.cmple(DVec3::ONE).all()).then_some(rel * last)
            }
        }
    }

    /// The trilinear sample at world point `x` (the f64 twin of the WGSL, over the same f32
    /// samples), before `strength`.
    pub fn sample(&self, x: DVec3) -> DVec3 {
        let Some(u) = self.node_coordinates(x) else {
            return DVec3::ZERO;
        };
        let g = &self.grid;
        let [nx, ny, nz] = g.counts;
        let cell = |u: f64, n: u32| (u.floor().max(0.0) as u32).min(n - 2);
        let (i, j, k) = (cell(u.x, nx), cell(u.y, ny), cell(u.z, nz));
        let f = u - DVec3::new(f64::from(i), f64::from(j), f64::from(k));
        let node = |di: u32, dj: u32, dk: u32| {
            let at = ((k + dk) * ny + (j + dj)) * nx + (i + di);
            DVec3::from_array(g.samples[at as usize].map(f64::from))
        };
        let along_x = |dj, dk| node(0, dj, dk).lerp(node(1, dj, dk), f.x);
        let along_y = |dk| along_x(0, dk).lerp(along_x(1, dk), f.y);
        along_y(0).lerp(along_y(1), f.z)
    }
}

impl ForceTerm for VectorFieldTerm {
    fn gpu_data(&self) -> Option<Vec<f32>> {
        Some(self.data())
    }
    fn origins(&self) -> &[usize] {
        &self.origins
    }

    fn describe(&self) -> String {
        let [nx, ny, nz] = self.grid.counts;
        format!(
            "VectorField {nx}x{ny}x{nz} nodes over {}..{}, strength {}, offset {}, scale {}, outside {:?}",
            self.grid.min, self.grid.max, self.strength, self.offset, self.scale, self.outside
        )
    }

    fn can_act(&self) -> bool {
        self.strength != 0.0
            && self
                .grid
                .samples
                .iter()
                .any(|s| s.iter().any(|&c| c != 0.0))
    }

    fn emit_wgsl(&self, w: &mut Writer) {
        let g = &self.grid;
        let [nx, ny, nz] = g.counts;
        w.comment("An imported vector field (FGA): trilinear between its nodes, from force_data.");
        w.block("", |w| {
            w.line(format!(
                "let rel = ((x - {}) / {} - {}) / {};",
                vec3_lit(self.offset),
                f32_lit(self.scale),
                vec3_lit(g.min),
                vec3_lit(g.max - g.min)
            ));
            let last = format!("vec3<f32>({}.0, {}.0, {}.0)", nx - 1, ny - 1, nz - 1);
            match self.outside {
                Outside::Clamp => {
                    w.line(format!("let u = clamp(rel, vec3<f32>(0.0), vec3<f32>(1.0)) * {last};"))
                }
                Outside::Tile => w.line(format!("let u = (rel - floor(rel)) * {last};")),
                Outside::Zero => {
                    w.line("let inside = all(rel >= vec3<f32>(0.0)) && all(rel <= vec3<f32>(1.0));");
                    w.line(format!("let u = select(vec3<f32>(0.0), rel * {last}, inside);"));
                }
            }
            w.line(format!(
                "let cell = min(vec3<u32>(max(floor(u), vec3<f32>(0.0))), vec3<u32>({}u, {}u, {}u));",
                nx - 2,
                ny - 2,
                nz - 2
            ));
            w.line("let f = u - vec3<f32>(cell);");
            w.line(format!(
                "let base = (cell.z * {ny}u + cell.y) * {nx}u + cell.x;"
            ));
            w.line(format!("let dy = {nx}u;"));
            w.line(format!("let dz = {}u;", nx * ny));
            w.line("var corner: array<vec3<f32>, 8>;");
            w.block("for (var c = 0u; c < 8u; c++)", |w| {
                w.line("let at = 3u * (base + (c & 1u) + ((c >> 1u) & 1u) * dy + (c >> 2u) * dz);");
                w.line("corner[c] = vec3<f32>(force_data[at], force_data[at + 1u], force_data[at + 2u]);");
            });
            w.line("let x0 = mix(corner[0], corner[1], f.x);");
            w.line("let x1 = mix(corner[2], corner[3], f.x);");
            w.line("let x2 = mix(corner[4], corner[5], f.x);");
            w.line("let x3 = mix(corner[6], corner[7], f.x);");
            let scale = match self.outside {
                Outside::Zero => format!("select(0.0, {}, inside)", f32_lit(self.strength)),
                _ => f32_lit(self.strength),
            };
            w.line(format!(
                "a = a + {scale} * mix(mix(x0, x1, f.y), mix(x2, x3, f.y), f.z);"
            ));
        });
    }

    fn stiffness_is_estimate(&self) -> bool {
        true
    }

    /// The steepest change between neighbouring nodes, per metre of the world, times the
    /// strength: |∂a/∂x| bounds ω² of an oscillation the field can drive.
    fn stiffness(&self) -> Stiffness {
        let g = &self.grid;
        let [nx, ny, nz] = g.counts.map(|n| n as usize);
        let spacing = (g.max - g.min) * self.scale
            / DVec3::new((nx - 1) as f64, (ny - 1) as f64, (nz - 1) as f64);
        let at = |i: usize, j: usize, k: usize| {
            DVec3::from_array(g.samples[(k * ny + j) * nx + i].map(f64::from))
        };
        let mut steepest: f64 = 0.0;
        for k in 0..nz {
            for j in 0..ny {
                for i in 0..nx {
                    let here = at(i, j, k);
                    if i + 1 < nx {
                        steepest = steepest.max((at(i + 1, j, k) - here).length() / spacing.x);
                    }
                    if j + 1 < ny {
                        steepest = steepest.max((at(i, j + 1, k) - here).length() / spacing.y);
                    }
                    if k + 1 < nz {
                        steepest = steepest.max((at(i, j, k + 1) - here).length() / spacing.z);
                    }
                }
            }
        }
        match steepest * self.strength.abs() {
            w2 if w2 > 0.0 => Stiffness::Oscillation(w2.sqrt()),
            _ => Stiffness::None,
        }
    }

    fn accel(&self, x: DVec3, _v: DVec3, _t: f64) -> DVec3 {
        self.strength * self.sample(x)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 2 x 3 x 2 field over [0, 2] x [0, 4] x [0, 1] whose x component is the node's x
    /// coordinate and y component its y coordinate: trilinear interpolation is exact for it.
    fn linear() -> Grid {
        let mut text = String::from("2,3,2,\n0,0,0,\n2,4,1,\n");
        for k in 0..2 {
            for j in 0..3 {
                for i in 0..2 {
                    text += &format!("{},{},{},\n", 2 * i, 2 * j, k);
                }
            }
        }
        parse_fga(&text).expect("a good field")
    }

    fn term(outside: Outside) -> VectorFieldTerm {
        VectorFieldTerm {
            grid: Arc::new(linear()),
            strength: 1.0,
            offset: DVec3::ZERO,
            scale: 1.0,
            outside,
            origins: vec![0],
        }
    }

    #[test]
    fn fga_text_is_read_and_sampled_trilinearly() {
        let t = term(Outside::Clamp);
        assert_eq!(t.grid.counts, [2, 3, 2]);
        assert_eq!(
            t.sample(DVec3::new(0.5, 3.0, 0.25)),
            DVec3::new(0.5, 3.0, 0.25)
        );
        // Clamped outside: the border's value.
        assert_eq!(
            t.sample(DVec3::new(5.0, -1.0, 0.5)),
            DVec3::new(2.0, 0.0, 0.5)
        );
        assert_eq!(
            term(Outside::Zero).sample(DVec3::new(5.0, 1.0, 0.5)),
            DVec3::ZERO
        );
        // Tiled: one period (2 m in x) on, the same value.
        let tile = term(Outside::Tile);
        assert_eq!(
            tile.sample(DVec3::new(2.5, 1.0, 0.5)),
            tile.sample(DVec3::new(0.5, 1.0, 0.5))
        );
    }

    #[test]
    fn bad_fga_text_says_what_and_where() {
        let cases = [
            ("2,2", "ends before its node count along z"),
            ("2,1,2, 0,0,0, 1,1,1", "at least 2 on every axis"),
            ("2,2,2, 0,0,0, 1,0,1", "below its max"),
            (
                "2,2,2, 0,0,0, 1,1,1, 1,2,x",
                "number 12 (vector of node 0) is `x`",
            ),
            (
                "2,2,2, 0,0,0, 1,1,1, 1,2,3",
                "ends before its vector of node 1",
            ),
            ("2,2,2, 0,0,0, 1,1,1, NaN,0,0", "must be finite"),
            ("4096,4096,4096, 0,0,0, 1,1,1", "68719476736 nodes"),
        ];
        for (text, expected) in cases {
            let error = parse_fga(text).unwrap_err();
            assert!(error.contains(expected), "{text}: {error}");
        }
        let mut full = String::from("2,2,2,0,0,0,1,1,1");
        full += &",0".repeat(24);
        assert!(parse_fga(&full).is_ok());
        full += ",7";
        assert!(parse_fga(&full).unwrap_err().contains("one too many"));
    }
}

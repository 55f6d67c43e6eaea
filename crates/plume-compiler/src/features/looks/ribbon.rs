//! Ribbons that join particles (`render.ribbon`): the particles of a group drawn as strips,
//! each particle joined to the one spawned before it in its ribbon: lightning, worms, the trail
//! an emitter leaves as it moves. This module owns the option end to end: its schema and
//! checks, which ribbon a particle joins and where in it ([`Link`]), the table the spawn
//! kernels write (`emit_write`), the draw's vertex and fragment shaders
//! (`emit_draw`) and the f64 twin of which particles the draw joins
//! ([`Ribbon::chains`]).
//!
//! A particle's link is a key (which ribbon) and an ordinal (its place in it), fixed at spawn:
//! - spawned by emitter e as its k-th particle: key e and ordinal k, or with `split: Some(n)`
//!   key e + E · ⌊k / n⌋ (E emitters) and ordinal k mod n, so every n spawns start a ribbon;
//! - the c-th child of a firing of an event (count per firing C, fired every P steps, 1 for
//!   `Death` and `Collide`), spawned at step s: key the firing particle's id and ordinal
//!   ⌊s / P⌋ · C + c, so the children of one parent's successive firings follow one another.
//!
//! The spawn writes (slot, id + 1, key, ordinal) into entry `(key mod ribbons) · points + ordinal
//! mod points` of the table. The draw gives each entry one instance: the segment from the
//! entry before it in its row to it, drawn when both entries' particles still live in their
//! slots (the id matches), both would show as sprites, their keys agree and the ordinals follow
//! one another. So nothing is cleared: a dead particle's entry, or one overwritten by a newer
//! particle of the row, joins nothing. A ribbon with more than `points` live particles loses
//! its oldest joins; keys equal mod `ribbons` share a row and take each other's entries.
//!
//! Each point is pushed sideways by half its particle's size, across the line of sight and the
//! ribbon's direction there (from the point before it to the point after it, or the point
//! itself at an end), so two segments that share a point share its two vertices and the strip
//! has no gaps. Colour is the particle's, as its sprite would have it; the strip is soft across
//! its width, as a trail is.

use serde::Deserialize;

use crate::base::check::Checker;
use crate::base::path::ValuePath;
use crate::base::writer::{u32_lit, Writer};

/// `render.ribbon`: the group's particles drawn as strips joining each to the one spawned
/// before it in its ribbon, instead of sprites.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Ribbon {
    /// Most particles of one ribbon alive at once (2 to 4096): a row's entries.
    #[serde(default = "default_points")]
    pub points: u32,
    /// Most ribbons alive at once (1 to 65,536): the table's rows.
    #[serde(default = "default_ribbons")]
    pub ribbons: u32,
    /// A new ribbon every `split` particles an emitter spawns (its bursts: lightning's bolts);
    /// None: one ribbon per emitter.
    #[serde(default)]
    pub split: Option<u32>,
}

fn default_points() -> u32 {
    64
}

fn default_ribbons() -> u32 {
    1
}

/// Binding of the ribbon table in the compute module (the spawn kernels write it).
pub(crate) const RIBBON_TABLE_BINDING: u32 = 17;

/// Binding of the ribbon table in the draw module (`vs_ribbon` reads it).
pub const RIBBON_DRAW_BINDING: u32 = 39;

/// Bytes of one table entry: slot, id + 1 (0: never written), key, ordinal.
pub(crate) const ENTRY_BYTES: u64 = 16;

/// Most entries of a table (rows × points): 64 MiB of them.
pub(crate) const TABLE_MOST: u64 = 1 << 22;

/// Vertices of one segment: a 4-vertex strip, two at each end.
pub const SEGMENT_VERTICES: u32 = 4;

/// The CPU's model of the ribbon table: per entry, the id and link written there last.
pub type Table = Vec<Option<(u32, Link)>>;

/// The render fields a ribbon does not draw, and what each would draw.
pub(crate) const CLASHES: [(&str, &str); 5] = [
    ("trail", "trails"),
    ("texture", "texture"),
    ("size_y", "separate heights"),
    ("rotation", "turned sprites"),
    ("orient", "oriented sprites"),
];

/// Which ribbon a particle joins and its place in it.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Link {
    /// The ribbon.
    pub key: u32,
    /// Its place: a particle joins the one of its key whose ordinal is one less.
    pub ordinal: u32,
}

impl Ribbon {
    /// Checks the sizes, and that the look is one a ribbon draws: `set(field)` says whether
    /// the group's `render.FIELD` is given (for `orient`: other than `Camera`), and `sort`
    /// whether it sorts. `root` is the group's path.
    pub(crate) fn check(
        &self,
        root: &ValuePath,
        set: &dyn Fn(&str) -> bool,
        sort: bool,
        c: &mut Checker,
    ) {
        let path = &root.field("render").field("ribbon");
        if !(2..=4096).contains(&self.points) {
            c.error(
                &path.field("points"),
                format!(
                    "must be 2 to 4096 (the most particles of one ribbon alive at once), got {}",
                    self.points
                ),
            );
        }
        if !(1..=65_536).contains(&self.ribbons) {
            c.error(
                &path.field("ribbons"),
                format!(
                    "must be 1 to 65536 (the most ribbons alive at once), got {}",
                    self.ribbons
                ),
            );
        }
        let entries = u64::from(self.points) * u64::from(self.ribbons);
        if entries > TABLE_MOST {
            c.error(
                &path.field("ribbons"),
                format!("ribbons × points is {entries}, more than the table's {TABLE_MOST} entries (64 MiB)"),
            );
        }
        if self.split == Some(0) {
            c.error(&path.field("split").inner(), "must be at least 1 particle");
        }
        for (field, what) in CLASHES {
            if set(field) {
                c.error(
                    &root.field("render").field(field),
                    format!("a group drawn as ribbons (render.ribbon) draws no {what}; leave {field} out or draw sprites"),
                );
            }
        }
        if sort {
            c.error(
                &root.field("sort"),
                "a group drawn as ribbons (render.ribbon) is drawn in ribbon order, not sorted by depth; leave sort out",
            );
        }
    }

    /// Entries of the table: rows × points.
    pub fn entries(&self) -> u32 {
        self.ribbons * self.points
    }

    /// Bytes of the table.
    pub fn table_bytes(&self) -> u64 {
        u64::from(self.entries()) * ENTRY_BYTES
    }

    /// The link of emitter `e`'s (of `emitters`) `k`-th spawn.
    pub fn emitted(&self, e: u32, emitters: u32, k: u32) -> Link {
        match self.split {
            Some(n) => Link {
                key: e.wrapping_add(emitters.wrapping_mul(k / n.max(1))),
                ordinal: k % n.max(1),
            },
            None => Link { key: e, ordinal: k },
        }
    }

    /// The link of the `c`-th child of a firing by particle `parent`, spawned at `step` by an
    /// event of `count` children per firing that fires every `period` steps.
    pub fn child(parent: u32, step: u64, period: u32, count: u32, c: u32) -> Link {
        Link {
            key: parent,
            ordinal: ((step as u32) / period.max(1))
                .wrapping_mul(count)
                .wrapping_add(c),
        }
    }

    /// The table entry a link is written to.
    pub fn entry(&self, link: Link) -> u32 {
        (link.key % self.ribbons) * self.points + link.ordinal % self.points
    }

    /// An empty table (the CPU's model of the GPU's: per entry, the id and link written last).
    pub fn table(&self) -> Table {
        vec![None; self.entries() as usize]
    }

    /// Writes particle `id`'s entry into `table`, as its spawn does.
    pub fn write(&self, table: &mut [Option<(u32, Link)>], id: u32, link: Link) {
        table[self.entry(link) as usize] = Some((id, link));
    }

    /// The f64 twin of the draw's joins, from the table the spawns wrote (in id order, as
    /// [`Self::write`]); `shows(id)` says whether the particle lives and would show as a
    /// sprite. Returns the ribbons as the draw joins them: runs of ids, each joined to the
    /// next, oldest first, every run at least two long, in table order.
    pub fn chains(
        &self,
        table: &[Option<(u32, Link)>],
        shows: &dyn Fn(u32) -> bool,
    ) -> Vec<Vec<u32>> {
        let p = self.points as usize;
        let joined = |a: Option<(u32, Link)>, b: Option<(u32, Link)>| match (a, b) {
            (Some((ia, la)), Some((ib, lb))) => {
                la.key == lb.key
                    && lb.ordinal == la.ordinal.wrapping_add(1)
                    && shows(ia)
                    && shows(ib)
            }
            _ => false,
        };
        let mut chains = Vec::new();
        for row in 0..self.ribbons as usize {
            let at = |j: usize| table[row * p + j % p];
            // Start a chain at every entry joined to the next but not to the one before.
            for j in 0..p {
                if joined(at(j + p - 1), at(j)) || !joined(at(j), at(j + 1)) {
                    continue;
                }
                let mut chain = vec![at(j).map(|e| e.0).unwrap_or_default()];
                let mut k = j;
                while joined(at(k), at(k + 1)) && chain.len() < p {
                    k += 1;
                    chain.push(at(k).map(|e| e.0).unwrap_or_default());
                }
                chains.push(chain);
            }
        }
        chains
    }

    /// Emits, in a spawn kernel that has stored particle `id` in `slot`, the write of its table
    /// entry for the link (`key`, `ordinal`: u32 WGSL expressions).
    pub(crate) fn emit_write(&self, w: &mut Writer, key: &str, ordinal: &str) {
        w.comment("Its ribbon's entry (features/looks/ribbon.rs): slot, id + 1, key, ordinal.");
        w.line(format!("let ribbon_key = {key};"));
        w.line(format!("let ribbon_ordinal = {ordinal};"));
        w.line(format!(
            "ribbon_table[(ribbon_key % {}) * {} + ribbon_ordinal % {}] = vec4<u32>(slot, id + 1u, ribbon_key, ribbon_ordinal);",
            u32_lit(self.ribbons),
            u32_lit(self.points),
            u32_lit(self.points)
        ));
    }

    /// The WGSL of emitter spawn k's link, with `e` and `k` in scope.
    pub(crate) fn emitted_wgsl(&self, emitters: u32) -> (String, String) {
        match self.split {
            Some(n) => (
                format!("e + {} * (k / {})", u32_lit(emitters), u32_lit(n)),
                format!("k % {}", u32_lit(n)),
            ),
            None => ("e".into(), "k".into()),
        }
    }

    /// The WGSL of an event child's link (the twin of [`Self::child`]), in the child spawn
    /// where the record `r` (whose velocity's w holds the parent's id, `EventIr::passes_id`),
    /// the child's place `c` in its firing and `params.step` are in scope, for an event of
    /// `count` children fired every `period` steps.
    pub(crate) fn child_wgsl(&self, period: u32, count: u32) -> (String, String) {
        (
            "bitcast<u32>(r.v.w)".into(),
            format!(
                "(params.step / {}) * {} + c",
                u32_lit(period.max(1)),
                u32_lit(count)
            ),
        )
    }

    /// Emits the draw module's ribbon shaders, `vs_ribbon` and `fs_ribbon`, after `sprite_at`
    /// (which, with no slot list, takes a slot), `load_particle` and `DrawView`.
    pub(crate) fn emit_draw(
        &self,
        w: &mut Writer,
        capacity: u32,
        lit: Option<&crate::features::looks::lit::Lit>,
        blend: crate::features::looks::Blend,
    ) {
        w.line(format!(
            "@group(0) @binding({RIBBON_DRAW_BINDING}) var<storage, read> ribbon_table: array<vec4<u32>>;"
        ));
        w.line(format!(
            "const RIBBON_POINTS: u32 = {};",
            u32_lit(self.points)
        ));
        w.line(format!("const RIBBON_SLOTS: u32 = {};", u32_lit(capacity)));
        w.blank();
        w.comment("A table entry's particle: whether it lives in its slot and shows, its link, its sprite.");
        w.block("struct RibbonEnd", |w| {
            w.line("shows: bool,");
            w.line("key: u32,");
            w.line("ordinal: u32,");
            w.line("s: SpriteAt,");
        });
        w.blank();
        w.block("fn ribbon_end(entry: u32) -> RibbonEnd", |w| {
            w.line("let t = ribbon_table[entry];");
            w.line("var r: RibbonEnd;");
            w.line("r.shows = false;");
            w.line("r.key = t.z;");
            w.line("r.ordinal = t.w;");
            w.comment("Never written (id + 1 is 0), or its particle gone from the slot.");
            w.block(
                "if (t.y == 0u || t.x >= RIBBON_SLOTS || load_particle(t.x).id + 1u != t.y)",
                |w| w.line("return r;"),
            );
            w.line("r.s = sprite_at(t.x);");
            w.line("r.shows = r.s.visible;");
            w.line("return r;");
        });
        w.blank();
        w.comment(
            "Whether the draw joins `a` to `b`: both show, one key, b's ordinal next after a's.",
        );
        w.block(
            "fn ribbon_joined(a: RibbonEnd, b: RibbonEnd) -> bool",
            |w| {
                w.line(
                    "return a.shows && b.shows && a.key == b.key && b.ordinal == a.ordinal + 1u;",
                );
            },
        );
        w.blank();
        if lit.is_some() {
            crate::features::looks::lit::emit_card_normal_fn(w);
            w.blank();
        }
        w.block("struct StripVertex", |w| {
            w.line("@builtin(position) clip: vec4<f32>,");
            w.line("@location(0) across: f32,");
            w.line("@location(1) color: vec4<f32>,");
        });
        w.blank();
        w.comment("Instance i: the segment from the entry before entry i in its row to entry i; vertices 0 and 1 at its first end, 2 and 3 at its second, on sides -1 and +1.");
        w.line("@vertex");
        w.block(
            "fn vs_ribbon(@builtin(vertex_index) vertex: u32, @builtin(instance_index) instance: u32) -> StripVertex",
            |w| {
                w.line("var out: StripVertex;");
                w.line("out.clip = HIDDEN;");
                w.line("out.across = 0.0;");
                w.line("out.color = vec4<f32>(0.0);");
                w.line("let base = instance - instance % RIBBON_POINTS;");
                w.line("let j = instance - base;");
                w.line("let a = ribbon_end(base + (j + RIBBON_POINTS - 1u) % RIBBON_POINTS);");
                w.line("let b = ribbon_end(instance);");
                w.block("if (!ribbon_joined(a, b))", |w| w.line("return out;"));
                w.comment("The point beyond this end, when the ribbon goes on there (else the end itself): the direction runs from the point before to the point after.");
                w.line("var here = a.s;");
                w.line("var before = a.s.center.xyz;");
                w.line("var after = b.s.center.xyz;");
                w.block("if (vertex >= 2u)", |w| {
                    w.line("here = b.s;");
                    w.line("let next = ribbon_end(base + (j + 1u) % RIBBON_POINTS);");
                    w.line("before = a.s.center.xyz;");
                    w.line("after = select(b.s.center.xyz, next.s.center.xyz, ribbon_joined(b, next));");
                });
                w.block("else", |w| {
                    w.line("let prev = ribbon_end(base + (j + RIBBON_POINTS - 2u) % RIBBON_POINTS);");
                    w.line("before = select(a.s.center.xyz, prev.s.center.xyz, ribbon_joined(prev, a));");
                    w.line("after = b.s.center.xyz;");
                });
                w.comment("Across the ribbon and the line of sight (the eye is the view space's origin).");
                w.line("let side = cross(before - after, here.center.xyz);");
                w.line("let len2 = dot(side, side);");
                w.line("let offset = select(vec3<f32>(0.0), side * (0.5 * here.size * inverseSqrt(max(len2, 1e-30))), len2 > 1e-30);");
                w.line("let sign = f32(vertex & 1u) * 2.0 - 1.0;");
                w.line("out.clip = draw.proj * vec4<f32>(here.center.xyz + sign * offset, 1.0);");
                w.line("out.across = sign;");
                w.line("out.color = here.color;");
                if let Some(lit) = lit {
                    if lit.shadow_per_particle() {
                        w.line("particle_shadow = shadow_visibility(here.center.xyz);");
                    }
                    w.comment("Lit as a flat card facing the eye, as a lit trail is.");
                    w.line("let n = card_normal(here.center.xyz, before - after);");
                    w.line("out.color = lit_color(here.color, received_light(n, here.center.xyz));");
                }
                w.line("return out;");
            },
        );
        w.blank();
        w.line("@fragment");
        w.block(
            "fn fs_ribbon(in: StripVertex) -> @location(0) vec4<f32>",
            |w| {
                w.comment("Soft across the strip: full on the centre line, zero at the edges.");
                w.line("let across = 1.0 - in.across * in.across;");
                w.line(format!("return {};", blend.strip_out_wgsl("across")));
            },
        );
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ribbon(points: u32, ribbons: u32, split: Option<u32>) -> Ribbon {
        Ribbon {
            points,
            ribbons,
            split,
        }
    }

    #[test]
    fn emitted_links_split_every_n_spawns() {
        let r = ribbon(64, 4, Some(64));
        assert_eq!(r.emitted(0, 1, 0), Link { key: 0, ordinal: 0 });
        assert_eq!(
            r.emitted(0, 1, 63),
            Link {
                key: 0,
                ordinal: 63
            }
        );
        assert_eq!(r.emitted(0, 1, 64), Link { key: 1, ordinal: 0 });
        assert_eq!(r.emitted(1, 2, 130), Link { key: 5, ordinal: 2 });
        let whole = ribbon(64, 1, None);
        assert_eq!(
            whole.emitted(1, 2, 130),
            Link {
                key: 1,
                ordinal: 130
            }
        );
    }

    #[test]
    fn children_of_successive_firings_follow_one_another() {
        // Fired every 3 steps, 2 children each: steps 9, 12, 15 give ordinals 6..11.
        let ords: Vec<u32> = [9u64, 12, 15]
            .iter()
            .flat_map(|&s| (0..2).map(move |c| Ribbon::child(7, s, 3, 2, c).ordinal))
            .collect();
        assert_eq!(ords, vec![6, 7, 8, 9, 10, 11]);
        assert_eq!(Ribbon::child(7, 9, 3, 2, 0).key, 7);
    }

    #[test]
    fn chains_join_consecutive_live_particles_of_a_key() {
        let r = ribbon(8, 2, None);
        // Key 0: ordinals 0..5 (ids 0..5); key 1: ordinals 3, 4 (ids 10, 11).
        let mut links: Vec<(u32, Link)> =
            (0..6).map(|k| (k, Link { key: 0, ordinal: k })).collect();
        links.extend([
            (10, Link { key: 1, ordinal: 3 }),
            (11, Link { key: 1, ordinal: 4 }),
        ]);
        let mut table = r.table();
        for (id, link) in links {
            r.write(&mut table, id, link);
        }
        // Id 2 is dead: the key-0 ribbon breaks in two.
        let chains = r.chains(&table, &|id| id != 2);
        assert_eq!(chains, vec![vec![0, 1], vec![3, 4, 5], vec![10, 11]]);
    }

    #[test]
    fn a_full_row_keeps_its_newest_points_and_does_not_join_round() {
        let r = ribbon(4, 1, None);
        let mut table = r.table();
        for k in 0..6 {
            r.write(&mut table, k, Link { key: 0, ordinal: k });
        }
        // Ordinals 4 and 5 overwrote 0 and 1: the row holds 2, 3, 4, 5.
        assert_eq!(r.chains(&table, &|_| true), vec![vec![2, 3, 4, 5]]);
    }
}

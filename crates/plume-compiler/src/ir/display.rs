//! The IR's text form (`plume compile --emit ir`): what each group is after the passes.

use std::fmt;

use glam::DVec3;

use super::{EffectIr, ShapeIr};

impl fmt::Display for EffectIr {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let v = |v: DVec3| format!("({}, {}, {})", v.x, v.y, v.z);
        writeln!(f, "effect {:?}", self.name)?;
        writeln!(
            f,
            "  capacity {}  seed {} (mix {:#010x})",
            self.capacity, self.seed, self.seed_mix
        )?;
        writeln!(
            f,
            "  dt {} s  substeps {}  h {} s",
            self.dt,
            self.substeps,
            self.h()
        )?;
        writeln!(
            f,
            "  integrator {} ({})",
            self.integrator.name(),
            self.integrator_reason
        )?;
        if let Some(budget) = &self.accuracy {
            writeln!(f, "  {}", budget.reason())?;
        }
        match self.max_speed {
            Some(s) => writeln!(f, "  max_speed {s} m/s")?,
            None => writeln!(f, "  max_speed none")?,
        }
        writeln!(
            f,
            "  state {} ({})",
            if self.stateless.is_some() {
                "stateless"
            } else {
                "stateful"
            },
            self.state_reason
        )?;
        let attributes = self.attributes.describe(self.kept_attributes());
        if !attributes.is_empty() {
            writeln!(f, "  attributes")?;
            for line in attributes {
                writeln!(f, "    {line}")?;
            }
        }
        writeln!(f, "  emitters")?;
        for (i, e) in self.emitters.iter().enumerate() {
            let burst = match e.burst_range {
                Some((lo, hi)) => format!("{lo} to {hi} (drawn)"),
                None => e.burst.to_string(),
            };
            writeln!(
                f,
                "    [{i}] burst {burst} rate {}/s lifetime {:?} steps {:?}",
                e.rate, e.lifetime, e.lifetime_steps
            )?;
            if !e.timing.is_plain() {
                writeln!(f, "        timing {}", e.timing.describe())?;
            }
            match &e.shape {
                // The surface's thresholds and triangles are data, not something to read.
                ShapeIr::Mesh(m) => writeln!(
                    f,
                    "        shape Mesh `{}`: {} triangles, area {:.6} m², {}",
                    m.file,
                    m.triangles.len(),
                    m.area,
                    match &m.volume {
                        Some(v) => format!("in its volume ({} inside cells)", v.cells.len()),
                        None => "on its surface".to_string(),
                    }
                )?,
                shape => writeln!(f, "        shape {shape:?}")?,
            }
            writeln!(f, "        velocity {:?}", e.velocity)?;
        }
        writeln!(f, "  forces")?;
        if self.terms.is_empty() && self.flock.is_none() {
            writeln!(f, "    (none)")?;
        }
        for t in &self.terms {
            let t = t.as_dyn();
            writeln!(f, "    {}  <- forces{:?}", t.describe(), t.origins())?;
        }
        if let Some(flock) = &self.flock {
            writeln!(f, "    {}  <- forces[{}]", flock.describe(), flock.origin)?;
        }
        if let Some(field) = &self.field {
            writeln!(
                f,
                "    {}: Attractor, Vortex and noise terms sampled from it",
                field.describe()
            )?;
        }
        writeln!(f, "  collide")?;
        for c in &self.colliders {
            writeln!(
                f,
                "    {} restitution {} friction {}",
                c.surface.describe(),
                c.restitution,
                c.friction
            )?;
        }
        if !self.scene.is_empty() {
            writeln!(f, "  scene (drawn, not simulated)")?;
            for m in &self.scene {
                writeln!(
                    f,
                    "    {} ({} triangles) offset ({}, {}, {}) scale {}",
                    m.file,
                    m.mesh.triangles.len(),
                    m.offset.x,
                    m.offset.y,
                    m.offset.z,
                    m.scale
                )?;
            }
        }
        writeln!(f, "  kill")?;
        for k in &self.kills {
            writeln!(f, "    {k:?}")?;
        }
        writeln!(
            f,
            "  render {:?} background {} colour {:?} size {:?}",
            self.render.blend,
            v(self.render.background),
            self.render.color,
            self.render.size
        )?;
        if let Some(h) = &self.render.size_y {
            writeln!(f, "  size_y {h:?}")?;
        }
        if let Some(a) = &self.render.alpha {
            writeln!(f, "  alpha {a:?}")?;
        }
        if self.render.orient != crate::features::looks::orient::OrientIr::Camera {
            writeln!(f, "  orient {:?}", self.render.orient)?;
        }
        if let Some(t) = &self.render.texture {
            writeln!(f, "  texture {t:?}")?;
        }
        if let Some(r) = &self.render.rotation {
            writeln!(f, "  rotation {r:?}")?;
        }
        if let Some(d) = self.render.soft {
            writeln!(f, "  soft {d} m")?;
        }
        if let Some(e) = &self.render.by.color {
            writeln!(f, "  color_by: {} nodes", e.size())?;
        }
        if let Some(e) = &self.render.by.alpha {
            writeln!(f, "  alpha_by: {} nodes", e.size())?;
        }
        if let Some(e) = &self.render.by.size {
            writeln!(f, "  size_by: {} nodes", e.size())?;
        }
        if let Some(g) = self.render.glow {
            writeln!(f, "  glow {g:?}")?;
        }
        if let Some(lit) = &self.render.lit {
            writeln!(
                f,
                "  lit {:?} normals, wrap {}, emissive {}{}; {}",
                lit.normals,
                lit.wrap,
                lit.emissive,
                if lit.shadows {
                    ", reads a shadow map"
                } else {
                    ""
                },
                self.lights
            )?;
            for map in &self.render.lit_maps {
                writeln!(f, "  lit map {map:?}")?;
            }
        }
        if let Some(light) = &self.render.light {
            writeln!(f, "  gives off light {light:?}")?;
        }
        if let Some(m) = &self.render.mesh {
            writeln!(f, "  mesh {m:?}")?;
        }
        if let Some(r) = &self.render.ribbon {
            writeln!(f, "  {r:?}, a {}-byte table", r.table_bytes())?;
        }
        if let Some(t) = &self.render.trail {
            writeln!(
                f,
                "  trail {} points, a sample every {} steps, width {:?} colour {:?}",
                t.points, t.every, t.width, t.color
            )?;
        }
        for e in &self.events {
            match (e.stream, e.target) {
                (Some(stream), Some(target)) => write!(
                    f,
                    "  fires event {stream} on {:?} into group {target} (firings {:?})",
                    e.trigger, e.ordering
                )?,
                _ => write!(f, "  fires an event on {:?}", e.trigger)?,
            }
            match e.report {
                0 => writeln!(f)?,
                most => writeln!(f, ", reported (at most {most} a readback)")?,
            }
        }
        for e in &self.event_inputs {
            writeln!(
                f,
                "  fed by event {}: {} per firing from emitters[{}], inherit_velocity {}, inherit_color {}, up to {} firings a step",
                e.stream, e.count, e.emitter, e.inherit_velocity, e.inherit_color, e.parent_capacity
            )?;
        }
        writeln!(
            f,
            "  sort {}  camera eye {} target {} fov_y {}",
            self.sort,
            v(self.camera.eye),
            v(self.camera.target),
            self.camera.fov_y
        )
    }
}

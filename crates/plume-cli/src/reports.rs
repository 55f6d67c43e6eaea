//! `plume run --reports FILE`: every firing of the effect's reported events (`Event(..,
//! report: N)`) as rows of a CSV file, from the GPU's readbacks or from the f64 reference's
//! firings, in (group, event, step, id) order, so the two runs' files compare line by line.

use std::path::Path;

use plume_compiler::graph::CompiledGraph;
use plume_compiler::reference::Fired;
use plume_runtime::{Effect, EventReport, RuntimeError};

/// One reported firing: its group, event, step and particle id, position and velocity.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Row {
    pub group: usize,
    pub event: usize,
    pub step: u64,
    pub id: u32,
    pub position: [f64; 3],
    pub velocity: [f64; 3],
}

/// The firings a run reported, and the firings past an event's bound in one readback (the GPU
/// counts them and keeps `report` of them).
#[derive(Default)]
pub(crate) struct Reported {
    pub rows: Vec<Row>,
    /// (group, event, firings counted but not kept).
    pub missed: Vec<(usize, usize, u64)>,
}

/// Whether any event of `graph` is reported.
pub(crate) fn any(graph: &CompiledGraph) -> bool {
    graph
        .groups
        .iter()
        .any(|g| g.effect.ir.events.iter().any(|e| e.report > 0))
}

impl Reported {
    /// Adds what a GPU readback brought.
    pub(crate) fn take_gpu(&mut self, reports: Vec<EventReport>) {
        for r in reports {
            if r.missed() > 0 {
                self.missed.push((r.group, r.event, r.missed()));
            }
            self.rows.extend(r.firings.iter().map(|f| Row {
                group: r.group,
                event: r.event,
                step: f.step,
                id: f.id,
                position: f.position.map(f64::from),
                velocity: f.velocity.map(f64::from),
            }));
        }
    }

    /// Adds the firings of every reported event of `graph` at the end of step `step`, as
    /// `fired(group, event)` (the f64 reference's) gives them.
    pub(crate) fn take_reference<'a>(
        &mut self,
        graph: &CompiledGraph,
        fired: impl Fn(usize, usize) -> &'a [Fired],
        step: u64,
    ) {
        for (g, group) in graph.groups.iter().enumerate() {
            for (j, event) in group.effect.ir.events.iter().enumerate() {
                if event.report > 0 {
                    self.rows.extend(fired(g, j).iter().map(|f| Row {
                        group: g,
                        event: j,
                        step,
                        id: f.id,
                        position: f.x.to_array(),
                        velocity: f.v.to_array(),
                    }));
                }
            }
        }
    }

    /// The CSV: header `group,event,step,id,x,y,z,vx,vy,vz`, rows in (group, event, step, id)
    /// order, groups by name.
    pub(crate) fn csv(&self, names: &[String]) -> Vec<u8> {
        let mut rows: Vec<&Row> = self.rows.iter().collect();
        rows.sort_by_key(|r| (r.group, r.event, r.step, r.id));
        let mut out = String::from("group,event,step,id,x,y,z,vx,vy,vz\n");
        for r in rows {
            let [x, y, z] = r.position;
            let [vx, vy, vz] = r.velocity;
            out.push_str(&format!(
                "{},{},{},{},{x},{y},{z},{vx},{vy},{vz}\n",
                names[r.group], r.event, r.step, r.id
            ));
        }
        out.into_bytes()
    }
}

/// Runs `steps` steps of `sim` one at a time, reading its reports back after each (the
/// readings of the last steps come back in the frames after, which run no step), and calls
/// `each` after every step.
pub(crate) fn run_gpu(
    sim: &mut Effect,
    steps: u64,
    mut each: impl FnMut(&mut Effect, u64) -> Result<(), RuntimeError>,
) -> Result<Reported, RuntimeError> {
    let mut reported = Reported::default();
    // A copy comes back two frames after it was recorded (mapped in the next, taken in the
    // one after), and the last step's copy is recorded in its own frame.
    const FLUSH: u64 = 3;
    let gpu = sim.gpu().clone();
    for done in 1..=steps + FLUSH {
        let mut encoder = gpu.device.create_command_encoder(&Default::default());
        sim.advance(&mut encoder, u64::from(done <= steps))?;
        reported.take_gpu(sim.watch_reports(&mut encoder)?);
        gpu.queue.submit([encoder.finish()]);
        gpu.wait()?;
        if done <= steps {
            each(sim, done)?;
        }
    }
    Ok(reported)
}

/// Writes `reported` to `path` (atomically; never over the effect file).
pub(crate) fn write(
    path: &Path,
    reported: &Reported,
    names: &[String],
    effect_file: &Path,
) -> Result<(), String> {
    plume_runtime::outputs::write_atomically(path, &reported.csv(names), &[effect_file])
}

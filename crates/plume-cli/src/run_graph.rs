//! `plume run` for an effect with groups and events: every group simulated together (on the
//! GPU, or with `--cpu-reference` the f64 reference graph), a summary per group, and an export
//! that names each particle's group.

use std::process::ExitCode;
use std::time::Instant;

use plume_compiler::graph::CompiledGraph;
use plume_compiler::reference::{ParticleRecord, ReferenceGraph, Totals};
use plume_runtime::export::{export_groups, summarize};
use plume_runtime::{Gpu, GpuChoice, GraphInstance, RuntimeError};

use crate::run::{progress_bar, Order, RunArgs};

struct GroupOutcome {
    name: String,
    totals: Totals,
    records: Vec<ParticleRecord>,
}

fn simulate(
    args: &RunArgs,
    graph: CompiledGraph,
) -> Result<(String, Vec<GroupOutcome>, f64), RuntimeError> {
    let names: Vec<String> = graph.groups.iter().map(|g| g.name.clone()).collect();
    let bar = progress_bar(args.steps, args.json);
    let start = Instant::now();
    if args.cpu_reference {
        bar.set_message("cpu reference");
        let mut sim = ReferenceGraph::new(&graph);
        for _ in 0..args.steps {
            sim.step();
            bar.inc(1);
        }
        bar.finish_and_clear();
        let seconds = start.elapsed().as_secs_f64();
        let groups = names
            .into_iter()
            .enumerate()
            .map(|(g, name)| GroupOutcome {
                name,
                totals: sim.totals(g),
                records: sim.records(g),
            })
            .collect();
        return Ok(("cpu reference (f64)".into(), groups, seconds));
    }
    let gpu = Gpu::new(&GpuChoice {
        backend: args.backend.clone(),
    })?;
    bar.set_message("gpu");
    let mut sim = GraphInstance::new(&gpu, graph)?;
    let start = Instant::now();
    sim.run(args.steps, |done| bar.set_position(done))?;
    let seconds = start.elapsed().as_secs_f64();
    bar.finish_and_clear();
    let mut groups = Vec::new();
    for (g, name) in names.into_iter().enumerate() {
        groups.push(GroupOutcome {
            name,
            totals: sim.totals(g)?,
            records: sim.records(g)?,
        });
    }
    Ok((gpu.describe(), groups, seconds))
}

/// Runs `plume run` on a graph of groups.
pub fn run_graph(args: &RunArgs, name: &str, graph: CompiledGraph) -> ExitCode {
    if args.order == Order::Draw {
        eprintln!("{name}: error: --order draw: an effect with groups exports by group and id (each group sorts its own draw)");
        return ExitCode::FAILURE;
    }
    let dt = graph.groups[0].effect.ir.dt;
    let (engine, groups, seconds) = match simulate(args, graph) {
        Ok(x) => x,
        Err(e) => {
            eprintln!("{name}: error: {e}");
            return ExitCode::FAILURE;
        }
    };
    if let Some(path) = &args.export {
        let parts: Vec<(&str, &[ParticleRecord])> = groups
            .iter()
            .map(|g| (g.name.as_str(), g.records.as_slice()))
            .collect();
        if let Err(e) = export_groups(path, &parts, &[args.file.as_path()]) {
            eprintln!("error: {e}");
            return ExitCode::FAILURE;
        }
    }
    let steps = groups[0].totals.steps;
    if args.json {
        let per_group: Vec<serde_json::Value> = groups
            .iter()
            .map(|g| {
                let s = summarize(&g.records);
                let t = g.totals;
                serde_json::json!({
                    "name": g.name,
                    "alive": t.alive,
                    "spawned": t.spawned,
                    "died": t.died,
                    "dropped": t.dropped,
                    "nonfinite": s.nonfinite,
                    "bbox_min": [s.bbox_min.x, s.bbox_min.y, s.bbox_min.z],
                    "bbox_max": [s.bbox_max.x, s.bbox_max.y, s.bbox_max.z],
                    "mean_speed": s.mean_speed,
                })
            })
            .collect();
        let v = serde_json::json!({
            "steps": steps,
            "groups": per_group,
            "seconds": seconds,
            "adapter": engine,
        });
        println!("{v}");
        return ExitCode::SUCCESS;
    }
    println!("{name}");
    println!("  adapter     {engine}");
    println!(
        "  steps       {steps} ({:.3} s simulated, dt {dt} s)",
        steps as f64 * dt
    );
    println!(
        "  {:<12} {:>9} {:>9} {:>9} {:>9} {:>9}  mean speed",
        "group", "alive", "spawned", "died", "dropped", "nonfinite"
    );
    for g in &groups {
        let s = summarize(&g.records);
        let t = g.totals;
        println!(
            "  {:<12} {:>9} {:>9} {:>9} {:>9} {:>9}  {:.4} m/s",
            g.name, t.alive, t.spawned, t.died, t.dropped, s.nonfinite, s.mean_speed
        );
    }
    println!("  wall time   {seconds:.3} s");
    if let Some(path) = &args.export {
        let total: usize = groups.iter().map(|g| g.records.len()).sum();
        println!("  exported    {total} particles to {}", path.display());
    }
    ExitCode::SUCCESS
}

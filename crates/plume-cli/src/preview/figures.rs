//! The preview's on-screen text: the effect's figures (time, live and dropped particles, GPU
//! time per step and per draw), the compiler's choices and warnings, reload errors, and the
//! keys.

use super::overlay::Panel;
use super::state::Running;
use super::window::KEYS;

const WHITE: [f32; 4] = [0.92, 0.92, 0.92, 1.0];
const DIM: [f32; 4] = [0.65, 0.68, 0.72, 1.0];
const YELLOW: [f32; 4] = [1.0, 0.85, 0.35, 1.0];
const RED: [f32; 4] = [1.0, 0.42, 0.38, 1.0];
const GREEN: [f32; 4] = [0.5, 0.9, 0.55, 1.0];

impl Running {
    /// The on-screen text: figures, warnings, errors and the keys.
    pub(super) fn panels(&mut self) -> Vec<Panel> {
        let mut lines: Vec<(String, [f32; 4])> = Vec::new();
        if let Some(loaded) = &mut self.effect {
            let i = &loaded.effect;
            let state = if self.clock.paused { "  paused" } else { "" };
            lines.push((
                format!(
                    "{}   t = {:.2} s (step {})   speed x{}{state}",
                    self.file.name(),
                    i.time(),
                    i.steps_done(),
                    self.clock.scale
                ),
                WHITE,
            ));
            lines.push((loaded.about.clone(), DIM));
            // A stateless effect counts on the CPU; a stateful one's counters come back
            // from the GPU a frame or two late.
            let totals = match i.counters() {
                Some(_) => self.probe.totals,
                None => i.group_totals(0).ok(),
            };
            if let Some(t) = totals {
                let whose = match i.group_names() {
                    [_] => String::new(),
                    names => format!(" ({})", names[0]),
                };
                lines.push((
                    format!("live {}   dropped {}{whose}", t.alive, t.dropped),
                    WHITE,
                ));
            }
            let stateless = i.is_stateless();
            let steps = match (stateless, self.probe.step_ms) {
                (true, _) => "steps: bookkeeping only (stateless: no GPU work)".to_string(),
                (false, Some(ms)) => format!(
                    "steps {ms:.3} ms GPU ({} in that frame)",
                    self.probe.steps_timed
                ),
                (false, None) => "steps -".to_string(),
            };
            let timing = match self.probe.draw_ms {
                None if !self.gpu.has_timestamps() => format!(
                    "frame {:.1} ms (no GPU timestamps on this adapter)",
                    self.frame_ms
                ),
                draw => format!(
                    "{steps}   draw {}   frame {:.1} ms",
                    draw.map_or("-".into(), |d| format!("{d:.3} ms GPU")),
                    self.frame_ms
                ),
            };
            lines.push((timing, WHITE));
            if let Some(ms) = self.reload_ms {
                lines.push((
                    format!("reloaded: {ms:.0} ms from save to new frame"),
                    GREEN,
                ));
            }
            for w in loaded.warnings.lines().take(8) {
                lines.push((w.to_string(), YELLOW));
            }
        }
        if let Some(problem) = &self.problem {
            for l in problem.lines().take(14) {
                lines.push((l.to_string(), RED));
            }
            if self.effect.is_some() {
                lines.push(("(the last good effect keeps running)".into(), RED));
            }
        }
        let mut panels = vec![Panel {
            lines,
            bottom: false,
        }];
        if self.help {
            // The keys, grouped so that a line never splits one.
            panels.push(Panel {
                lines: vec![(KEYS.replace("   ", " | "), DIM)],
                bottom: true,
            });
        }
        panels
    }
}

//! The preview's on-screen text: lines of ASCII in an 8x8 bitmap font (`font8x8`, public domain)
//! drawn at twice its size, each block on a translucent panel, alpha-blended over the window.
//! Characters outside ASCII show as `?`; long lines wrap at the window's edge.

use wgpu::util::DeviceExt;

/// Pixels per character cell (the 8x8 glyphs drawn 2x).
pub const CELL: f32 = 16.0;
/// Space between the window's edge (and a panel's edge) and the text.
const MARGIN: f32 = 8.0;

/// A block of lines in one place on screen.
pub struct Panel {
    /// Lines, each with its colour (RGBA).
    pub lines: Vec<(String, [f32; 4])>,
    /// Which corner: top left (false) or bottom left (true).
    pub bottom: bool,
}

/// One quad: rect (x, y, width, height) in pixels, atlas rect (u0, v0, u1, v1) or u0 < 0 for a
/// solid quad, colour.
type Quad = [f32; 12];

const OVERLAY_WGSL: &str = r#"
struct Screen {
    size: vec2<f32>,
    pad: vec2<f32>,
}
@group(0) @binding(0) var<uniform> screen: Screen;
@group(0) @binding(1) var atlas: texture_2d<f32>;
@group(0) @binding(2) var atlas_sampler: sampler;

struct Out {
    @builtin(position) clip: vec4<f32>,
    @location(0) uv: vec2<f32>,
    @location(1) color: vec4<f32>,
    @location(2) solid: f32,
}

@vertex
fn vs(@builtin(vertex_index) v: u32, @location(0) rect: vec4<f32>, @location(1) uv: vec4<f32>,
      @location(2) color: vec4<f32>) -> Out {
    let corner = vec2<f32>(f32(v & 1u), f32((v >> 1u) & 1u));
    let p = rect.xy + corner * rect.zw;
    var out: Out;
    out.clip = vec4<f32>(p.x / screen.size.x * 2.0 - 1.0, 1.0 - p.y / screen.size.y * 2.0, 0.0, 1.0);
    out.uv = mix(uv.xy, uv.zw, corner);
    out.color = color;
    out.solid = select(0.0, 1.0, uv.x < 0.0);
    return out;
}

@fragment
fn fs(in: Out) -> @location(0) vec4<f32> {
    var a = 1.0;
    if (in.solid < 0.5) {
        a = textureSampleLevel(atlas, atlas_sampler, in.uv, 0.0).r;
    }
    return vec4<f32>(in.color.rgb, in.color.a * a);
}
"#;

/// The text renderer for one surface format.
pub struct Overlay {
    pipeline: wgpu::RenderPipeline,
    group: wgpu::BindGroup,
    screen: wgpu::Buffer,
}

impl Overlay {
    /// Builds the glyph atlas and the pipeline for `format` targets.
    pub fn new(device: &wgpu::Device, queue: &wgpu::Queue, format: wgpu::TextureFormat) -> Self {
        // 128 glyphs side by side, 8x8 each, one byte a pixel.
        let mut texels = vec![0u8; 128 * 8 * 8];
        for (c, rows) in font8x8::legacy::BASIC_LEGACY.iter().enumerate() {
            for (y, row) in rows.iter().enumerate() {
                for x in 0..8 {
                    // Bit 0 is the leftmost pixel.
                    if row >> x & 1 == 1 {
                        texels[y * 1024 + c * 8 + x] = 255;
                    }
                }
            }
        }
        let atlas = device.create_texture_with_data(
            queue,
            &wgpu::TextureDescriptor {
                label: Some("glyphs"),
                size: wgpu::Extent3d {
                    width: 1024,
                    height: 8,
                    depth_or_array_layers: 1,
                },
                mip_level_count: 1,
                sample_count: 1,
                dimension: wgpu::TextureDimension::D2,
                format: wgpu::TextureFormat::R8Unorm,
                usage: wgpu::TextureUsages::TEXTURE_BINDING,
                view_formats: &[],
            },
            wgpu::util::TextureDataOrder::LayerMajor,
            &texels,
        );
        let sampler = device.create_sampler(&wgpu::SamplerDescriptor {
            label: Some("glyphs"),
            ..Default::default()
        });
        let screen = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("overlay screen"),
            size: 16,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("overlay"),
            source: wgpu::ShaderSource::Wgsl(OVERLAY_WGSL.into()),
        });
        let pipeline = device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some("overlay"),
            layout: None,
            vertex: wgpu::VertexState {
                module: &module,
                entry_point: Some("vs"),
                compilation_options: Default::default(),
                buffers: &[Some(wgpu::VertexBufferLayout {
                    array_stride: 48,
                    step_mode: wgpu::VertexStepMode::Instance,
                    attributes: &wgpu::vertex_attr_array![0 => Float32x4, 1 => Float32x4, 2 => Float32x4],
                })],
            },
            primitive: wgpu::PrimitiveState {
                topology: wgpu::PrimitiveTopology::TriangleStrip,
                ..Default::default()
            },
            depth_stencil: None,
            multisample: Default::default(),
            fragment: Some(wgpu::FragmentState {
                module: &module,
                entry_point: Some("fs"),
                compilation_options: Default::default(),
                targets: &[Some(wgpu::ColorTargetState {
                    format,
                    blend: Some(wgpu::BlendState::ALPHA_BLENDING),
                    write_mask: wgpu::ColorWrites::ALL,
                })],
            }),
            multiview_mask: None,
            cache: None,
        });
        let view = atlas.create_view(&Default::default());
        let group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("overlay"),
            layout: &pipeline.get_bind_group_layout(0),
            entries: &[
                wgpu::BindGroupEntry {
                    binding: 0,
                    resource: screen.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 1,
                    resource: wgpu::BindingResource::TextureView(&view),
                },
                wgpu::BindGroupEntry {
                    binding: 2,
                    resource: wgpu::BindingResource::Sampler(&sampler),
                },
            ],
        });
        Self {
            pipeline,
            group,
            screen,
        }
    }

    /// Records the panels into `pass`, for a target of `width` x `height` pixels.
    pub fn draw(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        pass: &mut wgpu::RenderPass<'_>,
        (width, height): (u32, u32),
        panels: &[Panel],
    ) {
        let size = [width as f32, height as f32, 0.0, 0.0];
        let bytes: Vec<u8> = size.iter().flat_map(|x| x.to_le_bytes()).collect();
        queue.write_buffer(&self.screen, 0, &bytes);
        let quads = layout(panels, width as f32, height as f32);
        if quads.is_empty() {
            return;
        }
        let bytes: Vec<u8> = quads
            .iter()
            .flatten()
            .flat_map(|x| x.to_le_bytes())
            .collect();
        let instances = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("overlay quads"),
            contents: &bytes,
            usage: wgpu::BufferUsages::VERTEX,
        });
        pass.set_pipeline(&self.pipeline);
        pass.set_bind_group(0, &self.group, &[]);
        pass.set_vertex_buffer(0, instances.slice(..));
        pass.draw(0..4, 0..quads.len() as u32);
    }
}

/// Wraps `text` into lines of at most `columns` characters, between words where it can (a word
/// longer than a line is cut).
pub fn wrap(text: &str, columns: usize) -> Vec<String> {
    let columns = columns.max(1);
    let mut lines = vec![String::new()];
    for word in text.split(' ') {
        let line = lines.last_mut().expect("never empty");
        let len = line.chars().count();
        let word_len = word.chars().count();
        if len > 0 && len + 1 + word_len > columns {
            lines.push(String::new());
        } else if len > 0 {
            line.push(' ');
        }
        let mut chars: Vec<char> = word.chars().collect();
        while chars.len() > columns {
            let rest = chars.split_off(columns);
            let line = lines.last_mut().expect("never empty");
            line.extend(chars);
            lines.push(String::new());
            chars = rest;
        }
        lines.last_mut().expect("never empty").extend(chars);
    }
    lines
}

/// The quads of every panel: a translucent panel behind each block, then one quad per glyph.
fn layout(panels: &[Panel], width: f32, height: f32) -> Vec<Quad> {
    let columns = ((width - 4.0 * MARGIN) / CELL).floor().max(1.0) as usize;
    let mut quads = Vec::new();
    for panel in panels {
        let lines: Vec<(String, [f32; 4])> = panel
            .lines
            .iter()
            .flat_map(|(text, color)| wrap(text, columns).into_iter().map(|l| (l, *color)))
            .collect();
        if lines.is_empty() {
            continue;
        }
        let longest = lines
            .iter()
            .map(|(l, _)| l.chars().count())
            .max()
            .unwrap_or(0);
        let (w, h) = (
            longest as f32 * CELL + 2.0 * MARGIN,
            lines.len() as f32 * CELL + 2.0 * MARGIN,
        );
        let (x0, y0) = match panel.bottom {
            false => (MARGIN, MARGIN),
            true => (MARGIN, (height - MARGIN - h).max(MARGIN)),
        };
        quads.push([x0, y0, w, h, -1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.6]);
        for (row, (line, color)) in lines.iter().enumerate() {
            for (col, c) in line.chars().enumerate() {
                let code = if c.is_ascii() && !c.is_ascii_control() {
                    c as u32
                } else {
                    '?' as u32
                };
                if code == ' ' as u32 {
                    continue;
                }
                let u0 = code as f32 * 8.0 / 1024.0;
                quads.push([
                    x0 + MARGIN + col as f32 * CELL,
                    y0 + MARGIN + row as f32 * CELL,
                    CELL,
                    CELL,
                    u0,
                    0.0,
                    u0 + 8.0 / 1024.0,
                    1.0,
                    color[0],
                    color[1],
                    color[2],
                    color[3],
                ]);
            }
        }
    }
    quads
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn text_wraps_and_lays_out_one_quad_per_visible_glyph() {
        assert_eq!(wrap("abcdef", 4), vec!["abcd", "ef"]);
        assert_eq!(wrap("", 4), vec![""]);
        assert_eq!(wrap("ab cd ef", 5), vec!["ab cd", "ef"]);
        assert_eq!(wrap("a bcdefgh", 4), vec!["a", "bcde", "fgh"]);
        let panel = Panel {
            lines: vec![("ab c".into(), [1.0; 4]), ("é".into(), [1.0; 4])],
            bottom: false,
        };
        let quads = layout(&[panel], 640.0, 360.0);
        // The panel, a, b, c (the space draws nothing), and a ? for the é.
        assert_eq!(quads.len(), 5);
        assert!(quads[0][4] < 0.0, "the panel is solid");
        assert_eq!(quads[4][4], '?' as u32 as f32 * 8.0 / 1024.0);
    }
}

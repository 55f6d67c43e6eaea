//! What a draw renders into: the colour format, the depth test and the sample count.

/// The depth test against a host's depth buffer.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct DepthTest {
    /// The depth attachment's format.
    pub format: wgpu::TextureFormat,
    /// Which fragments pass: `Less` for a standard depth buffer, `Greater` for reversed Z.
    pub compare: wgpu::CompareFunction,
}

/// What a draw renders into: the colour attachment's format and sample count, and the depth
/// attachment when the render pass has one (tested, never written). A pass with a depth
/// attachment needs a pipeline of that depth format: to draw over everything in such a pass,
/// use `with_depth_compare(format, CompareFunction::Always)`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct DrawTarget {
    /// The colour attachment's format.
    pub color_format: wgpu::TextureFormat,
    /// The depth test, when the render pass has a depth attachment.
    pub depth: Option<DepthTest>,
    /// Samples per pixel of the attachments (1: no multisampling).
    pub sample_count: u32,
    /// Whether `render.soft` effects fade against the scene's depth (needs a depth test and one
    /// sample). False draws them hard: a host whose depth is multisampled, or not bindable,
    /// draws them that way rather than not at all.
    pub soft: bool,
    /// Whether opaque and cut-out mesh particles (`render.mesh` with `Blend::Opaque` or
    /// `Blend::Mask`) write the depth they are drawn at, so that they hide one another, and
    /// what is drawn after them, with no sort. Needs a depth test and a pass whose depth
    /// attachment is writable (not read-only, so not bound for soft particles at once).
    /// Sprites never write depth.
    pub writes_depth: bool,
}

impl DrawTarget {
    /// A colour attachment of `format`, no depth buffer, one sample.
    pub fn new(color_format: wgpu::TextureFormat) -> Self {
        Self {
            color_format,
            depth: None,
            sample_count: 1,
            soft: true,
            writes_depth: false,
        }
    }

    /// Tests against a depth attachment of `format` with `Less` (a standard depth buffer).
    pub fn with_depth(self, format: wgpu::TextureFormat) -> Self {
        self.with_depth_compare(format, wgpu::CompareFunction::Less)
    }

    /// Tests against a depth attachment of `format` with `compare`.
    pub fn with_depth_compare(
        self,
        format: wgpu::TextureFormat,
        compare: wgpu::CompareFunction,
    ) -> Self {
        Self {
            depth: Some(DepthTest { format, compare }),
            ..self
        }
    }

    /// With soft particles faded against the scene's depth (`true`, the default) or drawn hard.
    pub fn with_soft(self, soft: bool) -> Self {
        Self { soft, ..self }
    }

    /// With opaque and cut-out mesh particles writing depth (`true`) or not (the default); see
    /// [`Self::writes_depth`].
    pub fn with_depth_writes(self, writes: bool) -> Self {
        Self {
            writes_depth: writes,
            ..self
        }
    }

    /// With `count` samples per pixel.
    pub fn with_samples(self, count: u32) -> Self {
        Self {
            sample_count: count,
            ..self
        }
    }
}

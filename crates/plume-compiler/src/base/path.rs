//! Value paths: how semantic diagnostics name the value they are about.

/// A path into the effect document, kept in two spellings: the one shown to users
/// (`forces[2] (Attractor).range`) and the one used to find the value in the source
/// (`forces[2].range`; variant names are not part of the document's structure).
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct ValuePath {
    /// Shown to users.
    pub display: String,
    /// Looked up in the [`crate::base::locate::SourceMap`].
    pub lookup: String,
}

impl ValuePath {
    /// The document root.
    pub fn root() -> Self {
        Self::default()
    }

    /// A named field below this path.
    pub fn field(&self, name: &str) -> Self {
        let join = |base: &str| {
            if base.is_empty() {
                name.to_string()
            } else {
                format!("{base}.{name}")
            }
        };
        Self {
            display: join(&self.display),
            lookup: join(&self.lookup),
        }
    }

    /// The `i`-th element of a list (or tuple) at this path.
    pub fn index(&self, i: usize) -> Self {
        Self {
            display: format!("{}[{i}]", self.display),
            lookup: format!("{}[{i}]", self.lookup),
        }
    }

    /// The `i`-th component of a tuple such as a vector; shown as `.x`, `.y`, `.z` for 3-tuples.
    pub fn component(&self, i: usize, name: &str) -> Self {
        Self {
            display: format!("{}.{name}", self.display),
            lookup: format!("{}.{i}", self.lookup),
        }
    }

    /// The single value inside a newtype variant such as `Gravity((0.0, -9.81, 0.0))`: the
    /// display path is unchanged, the source nests one level deeper.
    pub fn inner(&self) -> Self {
        Self {
            display: self.display.clone(),
            lookup: format!("{}.0", self.lookup),
        }
    }

    /// Marks which enum variant the value at this path is (display only).
    pub fn variant(&self, name: &str) -> Self {
        Self {
            display: format!("{} ({name})", self.display),
            lookup: self.lookup.clone(),
        }
    }
}

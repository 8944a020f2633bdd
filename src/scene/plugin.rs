//! A scene plugin as Mitsuba names it: its object tag, its `type`s, the properties it reads with
//! their defaults, and notes on what hppm does with it. The loader's messages, `hppm plugins` and
//! docs/scenes.md's table are made of these: the loader's own (src/loaders/plugins.rs) and each
//! BSDF unit's (src/bsdfs/).

/// One plugin (or several that read the same properties): its object tag, its `type`s, the
/// properties it reads and notes on what hppm does with it.
#[derive(Debug, Clone, Copy)]
pub struct Plugin {
    /// `integrator`, `sensor`, `sampler`, `film`, `rfilter`, `shape`, `bsdf`, `texture`,
    /// `emitter` or `spectrum`.
    pub object: &'static str,
    pub kinds: &'static [&'static str],
    pub properties: &'static [Property],
    pub notes: &'static str,
}

/// A property and its default as Mitsuba gives it ("" when it has none or the plugin needs it).
#[derive(Debug, Clone, Copy)]
pub struct Property {
    pub name: &'static str,
    pub default: &'static str,
}

pub const fn p(name: &'static str, default: &'static str) -> Property {
    Property { name, default }
}

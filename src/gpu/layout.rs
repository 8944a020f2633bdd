//! Rust structs that are uploaded to WGSL structs, described so that a test can hold each
//! against the composed naga module instead of trusting that the two were written alike:
//! `struct_layout!(PathTraceUniform => "PathTraceUniform" { sample_base, seed })` records the Rust size
//! and the named fields' offsets; `check` compares them with what naga lays out.

use wgpu::naga;

use super::shaders::ShaderFile;

/// One Rust struct and the WGSL struct it mirrors.
#[derive(Debug, Clone, Copy)]
pub struct StructLayout {
    pub rust: &'static str,
    pub wgsl: &'static str,
    /// A shader whose composed module contains the WGSL struct.
    pub shader: ShaderFile,
    pub size: usize,
    /// Fields that must sit at the same offset on both sides (padding fields left out: the two
    /// sides name them differently).
    pub fields: &'static [(&'static str, usize)],
    /// The Rust struct is only the head of the WGSL struct, which goes on with a runtime array
    /// (its first member after `fields` must start at `size`).
    pub head_only: bool,
}

/// `struct_layout!(RustType => "WgslName" in SHADER { field, ... })`, optionally `head` after the
/// braces for a struct the WGSL side continues with a runtime array.
#[macro_export]
macro_rules! struct_layout {
    ($ty:ty => $wgsl:literal in $shader:expr, { $($field:ident),* $(,)? } $($head:ident)?) => {
        $crate::gpu::layout::StructLayout {
            rust: stringify!($ty),
            wgsl: $wgsl,
            shader: $shader,
            size: std::mem::size_of::<$ty>(),
            fields: &[$((stringify!($field), std::mem::offset_of!($ty, $field))),*],
            head_only: $crate::struct_layout!(@head $($head)?),
        }
    };
    (@head) => { false };
    (@head head) => { true };
}

/// naga_oil decorates imported names (`Triangle` becomes `TriangleX_naga_oil_mod_...`).
fn matches_name(type_name: &str, wanted: &str) -> bool {
    type_name == wanted || type_name.starts_with(&format!("{wanted}X_naga_oil"))
}

impl StructLayout {
    /// Every difference between this layout and the WGSL struct's in `module`, as one message.
    pub fn check(&self, module: &naga::Module) -> Result<(), String> {
        let mut layouter = naga::proc::Layouter::default();
        layouter
            .update(module.to_ctx())
            .map_err(|e| format!("{}: naga cannot lay out the module: {e}", self.shader.path))?;
        let found = module.types.iter().find(|(_, ty)| {
            ty.name
                .as_deref()
                .is_some_and(|name| matches_name(name, self.wgsl))
        });
        let Some((handle, ty)) = found else {
            return Err(format!(
                "{}: no struct {} in the composed module",
                self.shader.path, self.wgsl
            ));
        };
        let naga::TypeInner::Struct { members, span } = &ty.inner else {
            return Err(format!(
                "{}: {} is not a struct",
                self.shader.path, self.wgsl
            ));
        };
        let align = layouter[handle].alignment.round_up(1) as usize;
        let mut problems = Vec::new();
        let name = format!("{} (Rust {})", self.wgsl, self.rust);
        if self.head_only {
            let after = self
                .fields
                .last()
                .and_then(|(last, _)| {
                    let at = members
                        .iter()
                        .position(|m| m.name.as_deref() == Some(last))?;
                    members
                        .iter()
                        .skip(at + 1)
                        .find(|m| !m.name.as_deref().is_some_and(|n| n.starts_with("pad")))
                })
                .map(|m| m.offset as usize);
            if after != Some(self.size) {
                problems.push(format!(
                    "{name}: its array starts at {after:?}, the Rust head is {} bytes",
                    self.size
                ));
            }
        } else {
            if *span as usize != self.size {
                problems.push(format!(
                    "{name}: {span} bytes in WGSL, {} in Rust",
                    self.size
                ));
            }
            // An array of the struct has the same stride on both sides only if the size is a
            // multiple of the WGSL alignment.
            if !self.size.is_multiple_of(align) {
                problems.push(format!(
                    "{name}: {} bytes is no multiple of its WGSL alignment {align}",
                    self.size
                ));
            }
        }
        for (field, offset) in self.fields {
            match members.iter().find(|m| m.name.as_deref() == Some(field)) {
                None => problems.push(format!("{name}: no WGSL member {field}")),
                Some(m) if m.offset as usize != *offset => problems.push(format!(
                    "{name}.{field}: offset {} in WGSL, {offset} in Rust",
                    m.offset
                )),
                Some(_) => {}
            }
        }
        if problems.is_empty() {
            Ok(())
        } else {
            Err(problems.join("\n"))
        }
    }
}

//! What a compiled kernel declares, read from its SPIR-V (rspirv-reflect): its
//! descriptor bindings with their names and kinds, and its workgroup size. Kernels are
//! bound by these names (src/gpu/kernel.rs), so no Rust code repeats a GLSL binding
//! number.
//!
//! A binding's name is the name of its GLSL variable: the variable of a texel buffer
//! (`uniform utextureBuffer light_vertices_a;` is `light_vertices_a`), and the block name
//! of a storage buffer declared without an instance name
//! (`buffer light_vertices_a { vec4 lv_a[]; };` is `light_vertices_a`).

use std::collections::HashMap;

use anyhow::{anyhow, bail, Result};
use ash::vk;
use rspirv_reflect::rspirv::dr::Operand;
use rspirv_reflect::rspirv::spirv::{Capability, Op};
use rspirv_reflect::{DescriptorType, Reflection};

/// One descriptor binding of set 0.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ReflectedBinding {
    pub binding: u32,
    pub name: String,
    pub descriptor_type: vk::DescriptorType,
}

/// A kernel's interface.
#[derive(Clone, Debug)]
pub struct KernelInterface {
    /// Bindings of descriptor set 0, by binding number.
    pub bindings: Vec<ReflectedBinding>,
    /// `local_size_x, y, z`.
    pub local_size: [u32; 3],
    /// The device features (names of src/gpu/context.rs's feature list) its SPIR-V
    /// capabilities need, of those vkvcm enables only where the device has them.
    pub needs: Vec<&'static str>,
}

/// The SPIR-V capabilities that need an optional device feature, with its name: a
/// module declaring one on a device without the feature is invalid, and a driver may
/// abort on it (SwiftShader: SIGILL), so no such module is created.
const FEATURE_CAPABILITIES: [(Capability, &str); 2] =
    [(Capability::Int64, super::SHADER_INT64), (Capability::Int64Atomics, super::SHADER_INT64_ATOMICS)];

impl KernelInterface {
    /// Fails, naming the feature, when the kernel `name` needs one that `has` says the
    /// device lacks.
    pub fn check_features(&self, name: &str, has: impl Fn(&str) -> bool) -> Result<()> {
        if let Some(f) = self.needs.iter().find(|f| !has(f)) {
            bail!("kernel {name} needs {f}, which this device lacks (or vkvcm did not enable)");
        }
        Ok(())
    }
}

/// Reflects the compute kernel `name` (for messages) from its SPIR-V words.
pub fn reflect(name: &str, spirv: &[u32]) -> Result<KernelInterface> {
    let r = Reflection::new_from_spirv(bytemuck::cast_slice(spirv))
        .map_err(|e| anyhow!("kernel {name}: cannot reflect its SPIR-V: {e}"))?;
    let (x, y, z) =
        r.get_compute_group_size().ok_or_else(|| anyhow!("kernel {name}: its SPIR-V declares no workgroup size"))?;
    let sets = r.get_descriptor_sets().map_err(|e| anyhow!("kernel {name}: cannot reflect its bindings: {e}"))?;
    if let Some(set) = sets.keys().find(|&&s| s != 0) {
        bail!("kernel {name} uses descriptor set {set}; vkvcm kernels use set 0 only");
    }
    let type_names = type_names_of_variables(&r);
    let mut bindings = Vec::new();
    for (&binding, info) in sets.get(&0).into_iter().flatten() {
        let descriptor_type = match info.ty {
            DescriptorType::STORAGE_BUFFER => vk::DescriptorType::STORAGE_BUFFER,
            DescriptorType::UNIFORM_TEXEL_BUFFER => vk::DescriptorType::UNIFORM_TEXEL_BUFFER,
            other => bail!("kernel {name}: binding {binding} ({}) is a {other:?}; vkvcm binds storage buffers and uniform texel buffers only", info.name),
        };
        let name_of = if info.name.is_empty() { type_names.get(&binding).cloned() } else { Some(info.name.clone()) };
        let Some(binding_name) = name_of.filter(|n| !n.is_empty()) else {
            bail!("kernel {name}: binding {binding} has no name to bind it by");
        };
        bindings.push(ReflectedBinding { binding, name: binding_name, descriptor_type });
    }
    let mut seen = HashMap::new();
    for b in &bindings {
        if let Some(other) = seen.insert(b.name.clone(), b.binding) {
            bail!("kernel {name}: bindings {other} and {} are both named {:?}", b.binding, b.name);
        }
    }
    let declared: Vec<Capability> =
        r.0.capabilities
            .iter()
            .filter_map(|i| match i.operands.first() {
                Some(Operand::Capability(c)) => Some(*c),
                _ => None,
            })
            .collect();
    let needs = FEATURE_CAPABILITIES.iter().filter(|(c, _)| declared.contains(c)).map(|&(_, f)| f).collect();
    Ok(KernelInterface { bindings, local_size: [x, y, z], needs })
}

/// For each variable of set 0 with a binding: the name of the block type it points to
/// (the name of a storage buffer declared without an instance name), by binding number.
fn type_names_of_variables(r: &Reflection) -> HashMap<u32, String> {
    let m = &r.0;
    let mut names: HashMap<u32, String> = HashMap::new();
    for i in m.debug_names.iter().filter(|i| i.class.opcode == Op::Name) {
        if let (Some(Operand::IdRef(id)), Some(Operand::LiteralString(s))) = (i.operands.first(), i.operands.get(1)) {
            names.insert(*id, s.clone());
        }
    }
    let mut binding_of: HashMap<u32, u32> = HashMap::new();
    for a in m.annotations.iter().filter(|a| a.class.opcode == Op::Decorate) {
        if let (Some(Operand::IdRef(id)), Some(Operand::Decoration(d)), Some(Operand::LiteralBit32(v))) =
            (a.operands.first(), a.operands.get(1), a.operands.get(2))
        {
            if *d == rspirv_reflect::rspirv::spirv::Decoration::Binding {
                binding_of.insert(*id, *v);
            }
        }
    }
    // Pointer type id -> pointee type id.
    let mut pointee: HashMap<u32, u32> = HashMap::new();
    for t in m.types_global_values.iter().filter(|t| t.class.opcode == Op::TypePointer) {
        if let (Some(id), Some(Operand::IdRef(inner))) = (t.result_id, t.operands.get(1)) {
            pointee.insert(id, *inner);
        }
    }
    let mut out = HashMap::new();
    for v in m.types_global_values.iter().filter(|t| t.class.opcode == Op::Variable) {
        let (Some(id), Some(ty)) = (v.result_id, v.result_type) else { continue };
        let Some(&binding) = binding_of.get(&id) else { continue };
        if let Some(name) = pointee.get(&ty).and_then(|inner| names.get(inner)) {
            out.insert(binding, name.clone());
        }
    }
    out
}

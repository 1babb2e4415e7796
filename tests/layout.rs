//! The Rust structs of src/render/gpu_types.rs and the GLSL structs of glsl/types.glsl
//! must have the same byte layout. Checked by compiling a probe kernel and reading the
//! member `Offset` and `ArrayStride` decorations out of its SPIR-V (no GPU needed).

use std::collections::HashMap;
use std::mem::{offset_of, size_of};

use vkvcm::gpu::shader;
use vkvcm::render::gpu_types::*;

/// struct name -> (member offsets by member name, array stride)
fn reflect(spirv: &[u32]) -> HashMap<String, (HashMap<String, u32>, Option<u32>)> {
    let mut names: HashMap<u32, String> = HashMap::new();
    let mut member_names: HashMap<(u32, u32), String> = HashMap::new();
    let mut offsets: HashMap<(u32, u32), u32> = HashMap::new();
    let mut strides: HashMap<u32, u32> = HashMap::new();
    let mut array_elem: HashMap<u32, u32> = HashMap::new();
    let string = |words: &[u32]| -> String {
        let bytes: Vec<u8> = words.iter().flat_map(|w| w.to_le_bytes()).take_while(|&b| b != 0).collect();
        String::from_utf8(bytes).unwrap()
    };
    let mut i = 5;
    while i < spirv.len() {
        let (count, op) = ((spirv[i] >> 16) as usize, spirv[i] & 0xffff);
        let w = &spirv[i + 1..i + count];
        match op {
            5 => {
                names.insert(w[0], string(&w[1..]));
            }
            6 => {
                member_names.insert((w[0], w[1]), string(&w[2..]));
            }
            71 if w[1] == 6 => {
                strides.insert(w[0], w[2]);
            }
            72 if w[2] == 35 => {
                offsets.insert((w[0], w[1]), w[3]);
            }
            29 => {
                array_elem.insert(w[0], w[1]); // OpTypeRuntimeArray result, element type
            }
            _ => {}
        }
        i += count;
    }
    let mut out: HashMap<String, (HashMap<String, u32>, Option<u32>)> = HashMap::new();
    for ((ty, member), off) in &offsets {
        let Some(sname) = names.get(ty) else { continue };
        let mname = member_names.get(&(*ty, *member)).cloned().unwrap_or_default();
        out.entry(sname.clone()).or_default().0.insert(mname, *off);
    }
    for (arr, elem) in &array_elem {
        if let (Some(stride), Some(sname)) = (strides.get(arr), names.get(elem)) {
            if let Some(e) = out.get_mut(sname) {
                e.1 = Some(*stride);
            }
        }
    }
    out
}

macro_rules! rust_layout {
    ($t:ty { $($f:ident),* }) => {
        (stringify!($t), size_of::<$t>() as u32, vec![$((stringify!($f), offset_of!($t, $f) as u32)),*])
    };
}

#[test]
fn rust_and_glsl_layouts_match() {
    let src = shader::source("tests/layout.comp").unwrap();
    let spirv = shader::compile_glsl_opt("tests/layout.comp", &src, &[], false).unwrap();
    let glsl = reflect(&spirv);
    let rust = [
        rust_layout!(GpuMaterial {
            diffuse,
            phong,
            mirror,
            emission,
            glossy,
            surface,
            maps,
            base_metallic,
            f0_roughness,
            medium,
            transmission,
            coat,
            layers,
            specular,
            sheen,
            sheen_maps,
            iridescence,
            iridescence_maps,
            anisotropy,
            diffuse_transmission,
            diffuse_transmission_maps,
            coat_normal,
            dispersion
        }),
        rust_layout!(GpuTextureRef { image, row0, row1 }),
        rust_layout!(GpuVertexAttributes { uv, color, tangent }),
        rust_layout!(GpuTriangle { material, light, first_vertex, _pad }),
        rust_layout!(GpuSphere { center_radius, info }),
        rust_layout!(GpuLight { a, b, c, d, radiance }),
        rust_layout!(GpuParams { cam_pos, cam_forward, cam_right, cam_up, scene_sphere, dims, misc }),
        rust_layout!(GpuAddresses {
            film,
            splat,
            light_vertices_a,
            light_vertices_b,
            grid_keys,
            grid_points,
            light_vertex_offsets,
            light_scratch_a,
            light_scratch_b
        }),
        rust_layout!(GpuSceneAddresses {
            vertex_attributes,
            texture_texels,
            env_texels,
            env_distribution,
            chunk_first
        }),
        rust_layout!(GpuPush {
            iteration,
            count,
            mis_vm,
            mis_vc,
            radius,
            light_paths,
            grid_buckets,
            paths_per_invocation,
            first_path
        }),
    ];
    for (name, size, fields) in rust {
        let (members, stride) = glsl.get(name).unwrap_or_else(|| panic!("struct {name} not found in SPIR-V"));
        assert_eq!(members.len(), fields.len(), "{name}: member count differs (GLSL {members:?})");
        for (f, off) in fields {
            assert_eq!(members.get(f), Some(&off), "{name}.{f}: Rust offset {off}, GLSL {:?}", members.get(f));
        }
        assert_eq!(*stride, Some(size), "{name}: Rust size {size}, GLSL array stride {stride:?}");
    }
}

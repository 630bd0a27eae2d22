//! GLSL → SPIR-V compilation shared by `build.rs` and the tests.
//!
//! Every `glsl/**/*.comp` is one kernel. `#include "x.glsl"` resolves first beside the
//! including file, then in `glsl/common/`. A kernel may declare extra variants with lines
//! of the form `//! variant NAME: DEFINE=VALUE OTHER` — each becomes its own SPIR-V module
//! `<kernel>__<NAME>` compiled with those defines, so variants never need copy-paste.
//! A kernel that takes buffers by address (`BUFFER_REF(` in glsl/common/address.glsl)
//! is compiled a second time with `SPLITRAY_DESCRIPTORS` defined, into its descriptor
//! twin: the same buffers as descriptors, which devices may read faster while each fits
//! one storage binding (src/vk/pipeline.rs chooses per dispatch).
//! Errors come back as `file:line: message`, the way glslang reports them.

use std::fmt;
use std::path::{Path, PathBuf};

/// One compiled SPIR-V module.
#[derive(Debug)]
pub struct CompiledKernel {
    /// `dir_stem` style identifier, e.g. `trace_brute_force` or `test_copy__wide`.
    pub name: String,
    pub source: PathBuf,
    pub spirv: Vec<u8>,
    /// The descriptor twin of a kernel that takes buffers by address.
    pub descriptor_twin: Option<Vec<u8>>,
}

/// Marks a kernel that takes buffers by address (glsl/common/address.glsl).
const BY_ADDRESS_MARK: &str = "BUFFER_REF(";

#[derive(Debug)]
pub struct ShaderError(pub String);

impl fmt::Display for ShaderError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for ShaderError {}

/// A variant request parsed from a `//! variant` line.
struct Variant {
    suffix: String,
    defines: Vec<(String, Option<String>)>,
}

fn parse_variants(source: &str) -> Vec<Variant> {
    let mut variants = vec![Variant {
        suffix: String::new(),
        defines: Vec::new(),
    }];
    for line in source.lines() {
        let Some(rest) = line.trim().strip_prefix("//! variant ") else {
            continue;
        };
        let Some((name, defs)) = rest.split_once(':') else {
            continue;
        };
        let defines = defs
            .split_whitespace()
            .map(|d| match d.split_once('=') {
                Some((k, v)) => (k.to_string(), Some(v.to_string())),
                None => (d.to_string(), None),
            })
            .collect();
        variants.push(Variant {
            suffix: format!("__{}", name.trim()),
            defines,
        });
    }
    variants
}

/// Identifier of a kernel from its path below the glsl root: `trace/brute_force.comp`
/// becomes `trace_brute_force`.
pub fn kernel_name(glsl_root: &Path, file: &Path) -> String {
    let rel = file.strip_prefix(glsl_root).unwrap_or(file);
    let mut name = rel
        .with_extension("")
        .to_string_lossy()
        .replace(['/', '\\', '-', '.'], "_");
    name.make_ascii_lowercase();
    name
}

/// Every `.comp` file below `glsl_root`, sorted for a stable build.
pub fn find_kernels(glsl_root: &Path) -> std::io::Result<Vec<PathBuf>> {
    let mut out = Vec::new();
    let mut stack = vec![glsl_root.to_path_buf()];
    while let Some(dir) = stack.pop() {
        for entry in std::fs::read_dir(&dir)? {
            let path = entry?.path();
            if path.is_dir() {
                stack.push(path);
            } else if path.extension().is_some_and(|e| e == "comp") {
                out.push(path);
            }
        }
    }
    out.sort();
    Ok(out)
}

/// Compiles one kernel file (all of its variants, and their descriptor twins).
pub fn compile_kernel(
    compiler: &shaderc::Compiler,
    glsl_root: &Path,
    file: &Path,
) -> Result<Vec<CompiledKernel>, ShaderError> {
    let source = std::fs::read_to_string(file)
        .map_err(|e| ShaderError(format!("{}: cannot read: {e}", file.display())))?;
    let common = glsl_root.join("common");
    let base_name = kernel_name(glsl_root, file);
    let twin = source.contains(BY_ADDRESS_MARK);
    let mut out = Vec::new();
    for mut variant in parse_variants(&source) {
        let spirv = compile_module(compiler, &source, file, &common, &variant.defines)?;
        let descriptor_twin = if twin {
            variant
                .defines
                .push(("SPLITRAY_DESCRIPTORS".to_string(), None));
            Some(compile_module(
                compiler,
                &source,
                file,
                &common,
                &variant.defines,
            )?)
        } else {
            None
        };
        out.push(CompiledKernel {
            name: format!("{base_name}{}", variant.suffix),
            source: file.to_path_buf(),
            spirv,
            descriptor_twin,
        });
    }
    Ok(out)
}

/// Compiles `source` (the text of `file`) with `defines` into SPIR-V bytes.
fn compile_module(
    compiler: &shaderc::Compiler,
    source: &str,
    file: &Path,
    common: &Path,
    defines: &[(String, Option<String>)],
) -> Result<Vec<u8>, ShaderError> {
    let mut options = shaderc::CompileOptions::new()
        .ok_or_else(|| ShaderError("shaderc: cannot create compile options".into()))?;
    options.set_target_env(
        shaderc::TargetEnv::Vulkan,
        shaderc::EnvVersion::Vulkan1_3 as u32,
    );
    options.set_target_spirv(shaderc::SpirvVersion::V1_6);
    options.set_source_language(shaderc::SourceLanguage::GLSL);
    options.set_optimization_level(shaderc::OptimizationLevel::Performance);
    options.set_generate_debug_info();
    for (k, v) in defines {
        options.add_macro_definition(k, v.as_deref());
    }
    let common = common.to_path_buf();
    options.set_include_callback(move |requested, _kind, requester, _depth| {
        let beside = Path::new(requester)
            .parent()
            .map(|p| p.join(requested))
            .filter(|p| p.is_file());
        let path = beside.unwrap_or_else(|| common.join(requested));
        match std::fs::read_to_string(&path) {
            Ok(content) => Ok(shaderc::ResolvedInclude {
                resolved_name: path.to_string_lossy().into_owned(),
                content,
            }),
            Err(e) => Err(format!(
                "cannot include \"{requested}\" (looked beside {requester} and in {}): {e}",
                common.display()
            )),
        }
    });
    let artifact = compiler
        .compile_into_spirv(
            source,
            shaderc::ShaderKind::Compute,
            &file.to_string_lossy(),
            "main",
            Some(&options),
        )
        .map_err(|e| ShaderError(e.to_string()))?;
    Ok(artifact.as_binary_u8().to_vec())
}

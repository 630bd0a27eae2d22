//! The build-time shader compiler reports errors as file:line and resolves includes.

// tools/shader_build.rs, the compiler build.rs runs.
#[path = "../../tools/shader_build.rs"]
#[allow(dead_code)]
mod build_tool;

use std::path::Path;

fn compile(root: &Path, file: &Path) -> Result<Vec<build_tool::CompiledKernel>, String> {
    let compiler = shaderc::Compiler::new().unwrap();
    build_tool::compile_kernel(&compiler, root, file).map_err(|e| e.to_string())
}

#[test]
fn compile_errors_carry_file_and_line() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::create_dir(dir.path().join("common")).unwrap();
    let file = dir.path().join("broken.comp");
    std::fs::write(
        &file,
        "#version 460\nlayout(local_size_x = 1) in;\nvoid main() {\n    undefined_thing = 1;\n}\n",
    )
    .unwrap();
    let err = compile(dir.path(), &file).unwrap_err();
    assert!(err.contains("broken.comp:4"), "{err}");
    assert!(err.contains("undefined_thing"), "{err}");
}

#[test]
fn errors_inside_included_files_name_the_included_file() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::create_dir(dir.path().join("common")).unwrap();
    std::fs::write(
        dir.path().join("common/bad.glsl"),
        "\n\nint f() { return nope; }\n",
    )
    .unwrap();
    let file = dir.path().join("k.comp");
    std::fs::write(
        &file,
        "#version 460\n#extension GL_GOOGLE_include_directive : require\n#include \"bad.glsl\"\nlayout(local_size_x = 1) in;\nvoid main() {}\n",
    )
    .unwrap();
    let err = compile(dir.path(), &file).unwrap_err();
    assert!(err.contains("bad.glsl:3"), "{err}");
}

#[test]
fn variants_compile_with_their_defines() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::create_dir(dir.path().join("common")).unwrap();
    let file = dir.path().join("v.comp");
    std::fs::write(
        &file,
        "#version 460\n//! variant wide: WIDTH=4\n#ifndef WIDTH\n#define WIDTH 1\n#endif\nlayout(local_size_x = WIDTH) in;\nvoid main() {}\n",
    )
    .unwrap();
    let kernels = compile(dir.path(), &file).unwrap();
    let names: Vec<_> = kernels.iter().map(|k| k.name.as_str()).collect();
    assert_eq!(names, ["v", "v__wide"]);
    assert_ne!(kernels[0].spirv, kernels[1].spirv);
}

#[test]
fn every_embedded_kernel_is_valid_spirv() {
    for k in splitray::shaders::ALL {
        assert_eq!(k.spirv.len() % 4, 0, "{}", k.name);
        assert_eq!(&k.spirv[..4], &0x0723_0203u32.to_le_bytes(), "{}", k.name);
    }
}

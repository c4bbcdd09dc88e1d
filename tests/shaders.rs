//! The shader sources themselves: GLSL ES 1.00 everywhere (the low-end path),
//! no texture reads in any vertex shader (the boards cannot do them), and
//! the terrain morph written the same way as its Rust mirror.

use std::path::Path;

fn shaders() -> Vec<(String, String)> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("shaders/gles");
    let mut out: Vec<(String, String)> = std::fs::read_dir(&dir)
        .expect("shaders/gles exists")
        .map(|entry| entry.expect("readable entry").path())
        .filter(|path| matches!(path.extension().and_then(|e| e.to_str()), Some("vert" | "frag")))
        .map(|path| {
            (
                path.file_name().unwrap().to_string_lossy().into_owned(),
                std::fs::read_to_string(&path).unwrap(),
            )
        })
        .collect();
    out.sort();
    out
}

/// The source without comments, so a comment may mention what code may not use.
fn code(source: &str) -> String {
    source.lines().map(|line| line.split("//").next().unwrap_or("")).collect::<Vec<_>>().join("\n")
}

#[test]
fn every_shader_is_glsl_es_100() {
    let all = shaders();
    assert!(all.len() >= 6, "found {} shaders", all.len());
    for (name, source) in &all {
        assert_eq!(
            source.lines().next(),
            Some("#version 100"),
            "{name} must start with #version 100"
        );
    }
}

#[test]
fn no_vertex_shader_reads_a_texture() {
    for (name, source) in shaders().iter().filter(|(name, _)| name.ends_with(".vert")) {
        let code = code(source);
        for word in ["sampler", "texture", "texelFetch"] {
            assert!(
                !code.contains(word),
                "{name} uses `{word}`: the target GPUs cannot read textures in vertex shaders"
            );
        }
    }
}

#[test]
fn terrain_morph_matches_its_rust_mirror() {
    let vert = std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("shaders/gles/terrain.vert"),
    )
    .unwrap();
    let rust =
        std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("src/lod/morph.rs"))
            .unwrap();
    assert!(code(&vert)
        .contains("clamp((distance - morph_band.x) / (morph_band.y - morph_band.x), 0.0, 1.0)"));
    assert!(
        code(&vert).contains("float end = sub_end * exp2(1.0 - band);")
            && code(&vert).contains("return vec2(end * start_share, end);")
    );
    assert!(
        code(&rust).contains("let end = sub_end * (1.0 - band as f32).exp2();")
            && code(&rust).contains("[end * start_share, end]")
    );
    assert!(
        code(&vert).contains("length(vec3(position, own - altitude))")
            && code(&vert).contains("float own = no_data ? a_height.y : a_height.x;"),
        "distance uses the unmorphed height (a post without data: its stand-in)"
    );
    assert!(code(&rust).contains("((distance - start) / (end - start)).clamp(0.0, 1.0)"));
}

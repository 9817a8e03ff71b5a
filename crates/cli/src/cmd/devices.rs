//! `glint info --devices`: the GPU adapters the GPU back end can use (docs/gpu.md).

/// The adapters as text (one line each) or JSON (an array of objects).
#[cfg(feature = "gpu")]
pub fn report(json: bool) -> anyhow::Result<String> {
    use std::fmt::Write as _;
    let adapters = glint_render::gpu::adapters();
    if json {
        let list: Vec<serde_json::Value> = adapters
            .iter()
            .map(|a| {
                serde_json::json!({
                    "name": a.name,
                    "backend": a.backend,
                    "device_type": a.device_type,
                    "driver": a.driver,
                    "max_texture_3d": a.max_texture_3d,
                    "compute": a.compute,
                    "hardware": a.hardware,
                })
            })
            .collect();
        return Ok(format!("{}\n", serde_json::to_string_pretty(&list)?));
    }
    let mut out = String::new();
    if adapters.is_empty() {
        writeln!(
            out,
            "no GPU adapter (Vulkan, Metal or DX12): --device auto renders on the CPU; \
             install the GPU's driver, or mesa-vulkan-drivers for lavapipe"
        )?;
    }
    for a in &adapters {
        let kind = if a.hardware { "hardware" } else { "software" };
        writeln!(
            out,
            "{}: {}, {} ({kind}), driver {}, max 3D texture {}, compute {}",
            a.name,
            a.backend,
            a.device_type,
            a.driver,
            a.max_texture_3d,
            if a.compute { "yes" } else { "no" }
        )?;
    }
    Ok(out)
}

/// Without the `gpu` feature there is no GPU back end to list adapters for.
#[cfg(not(feature = "gpu"))]
pub fn report(_json: bool) -> anyhow::Result<String> {
    anyhow::bail!("this glint was built without its `gpu` feature: no GPU back end")
}

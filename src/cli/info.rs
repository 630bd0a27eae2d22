//! `splitray info`.

use anyhow::Context;
use clap::Args;
use serde::Serialize;
use splitray::vk::{
    self, CapabilityInfo, Instance, InstanceDesc, LimitsInfo, PhysicalDeviceInfo, QueueFamilyInfo,
    StreamKind, StreamMapping, StreamPlacement,
};

#[derive(Debug, Args)]
pub struct InfoArgs {
    /// Print machine-readable JSON instead of text.
    #[arg(long)]
    json: bool,
    /// Mark this device (index or name substring) as the one `render` would use.
    #[arg(long, value_parser = clap::builder::NonEmptyStringValueParser::new())]
    device: Option<String>,
}

#[derive(Serialize)]
struct DeviceReport {
    #[serde(flatten)]
    info: PhysicalDeviceInfo,
    selected: bool,
    missing_requirements: Vec<String>,
    streams: StreamMapping,
}

#[derive(Serialize)]
struct InfoReport {
    validation_layer_available: bool,
    devices: Vec<DeviceReport>,
}

/// Every device `instance` lists, with what splitray makes of it; `device` marks the one
/// `render` would use.
fn report(instance: &Instance, device: Option<&str>) -> anyhow::Result<InfoReport> {
    let devices = vk::enumerate(instance)?;
    // Without a device named, none may be usable and the list is still wanted; a device
    // named that `render` would refuse is an error, as it would be there.
    let selected = match device {
        Some(_) => Some(vk::select(&devices, device)?.index),
        None => vk::select(&devices, None).ok().map(|d| d.index),
    };
    Ok(InfoReport {
        validation_layer_available: vk::validation_layer_available(),
        devices: devices
            .iter()
            .map(|d| DeviceReport {
                info: d.clone(),
                selected: Some(d.index) == selected,
                missing_requirements: d.missing_requirements(),
                streams: StreamMapping::plan(d, StreamPlacement::Spread),
            })
            .collect(),
    })
}

fn print_queue_families(families: &[QueueFamilyInfo]) {
    splitray::outln!("    queue families:");
    for q in families {
        let mut caps = vec![];
        if q.graphics {
            caps.push("graphics");
        }
        if q.compute {
            caps.push("compute");
        }
        if q.transfer {
            caps.push("transfer");
        }
        splitray::outln!(
            "      {}: {} queue(s), {}, timestamps {} bits",
            q.index,
            q.count,
            caps.join("+"),
            q.timestamp_valid_bits
        );
    }
}

fn print_streams(streams: &StreamMapping) {
    splitray::outln!("    streams:");
    for kind in StreamKind::ALL {
        let s = streams.slot(kind);
        splitray::outln!(
            "      {:<9} -> family {} queue {}",
            kind.name(),
            s.family,
            s.index
        );
    }
    if streams.is_single_queue() {
        splitray::outln!("      (one queue: streams are ordered by timeline semaphores on it)");
    }
}

fn print_limits(l: &LimitsInfo) {
    splitray::outln!(
        "    limits: maxStorageBufferRange {} MiB (kernels pass larger buffers by address), largest buffer {} MiB (maxBufferSize {} MiB, maxMemoryAllocationSize {} MiB), device-local memory {} MiB, shared memory {} KiB, workgroup invocations {}, subgroup size {} ({}..{}), push constants {} B, timestampPeriod {} ns",
        l.max_storage_buffer_range >> 20,
        l.max_buffer_size.min(l.max_memory_allocation_size) >> 20,
        l.max_buffer_size >> 20,
        l.max_memory_allocation_size >> 20,
        l.device_local_bytes >> 20,
        l.max_compute_shared_memory_size >> 10,
        l.max_compute_work_group_invocations,
        l.subgroup_size,
        l.min_subgroup_size,
        l.max_subgroup_size,
        l.max_push_constants_size,
        l.timestamp_period_ns
    );
}

fn print_calibrated_timestamps(time_domains: &[String]) {
    splitray::outln!(
        "    calibrated timestamps: {}",
        if time_domains.is_empty() {
            "none (timelines align GPU times at submission)".to_string()
        } else {
            format!("{} (timelines use them)", time_domains.join(", "))
        }
    );
}

fn print_features(c: &CapabilityInfo) {
    splitray::outln!(
        "    features: timeline semaphores {}, synchronization2 {}, maintenance4 {}, push descriptors {}, buffer device address {}, ray query {}, subgroup arithmetic {}, subgroup ballot+shuffle {}, full subgroups {}, 64-bit buffer atomics {}, host query reset {}",
        c.timeline_semaphore,
        c.synchronization2,
        c.maintenance4,
        c.push_descriptor,
        c.buffer_device_address,
        c.ray_query,
        c.subgroup_arithmetic,
        c.subgroup_ballot_shuffle,
        c.compute_full_subgroups,
        c.buffer_int64_atomics,
        c.host_query_reset
    );
}

fn print_device(d: &DeviceReport) {
    let i = &d.info;
    splitray::outln!(
        "\n[{}] {}{}\n    type {}, Vulkan {}, driver {} {}",
        i.index,
        i.name,
        if d.selected { "  (selected)" } else { "" },
        i.device_type,
        i.api_version,
        i.driver_name,
        i.driver_info
    );
    if !d.missing_requirements.is_empty() {
        splitray::outln!(
            "    cannot run splitray: lacks {}",
            d.missing_requirements.join(", ")
        );
    }
    print_queue_families(&i.queue_families);
    print_streams(&d.streams);
    print_limits(&i.limits);
    print_calibrated_timestamps(&i.calibrated_time_domains);
    print_features(&i.capabilities);
}

pub fn run(args: &InfoArgs) -> anyhow::Result<()> {
    let instance =
        Instance::new(InstanceDesc::default()).context("cannot create a Vulkan instance")?;
    let report = report(&instance, args.device.as_deref())?;
    if args.json {
        splitray::outln!("{}", serde_json::to_string_pretty(&report)?);
        return Ok(());
    }
    splitray::outln!(
        "validation layer: {}",
        if report.validation_layer_available {
            "available"
        } else {
            "not installed"
        }
    );
    for d in &report.devices {
        print_device(d);
    }
    Ok(())
}

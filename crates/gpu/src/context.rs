//! The headless device: adapter choice, optional features and limits.

use std::fmt;

/// Environment variable naming the adapter when no CLI option does (a case-insensitive
/// substring of the adapter name, or its index in the list printed by the error).
pub const ADAPTER_ENV: &str = "MANYLIGHTS_ADAPTER";

/// Errors of the GPU core.
#[derive(Debug, thiserror::Error)]
pub enum GpuError {
    /// No adapter matched, or none exists.
    #[error("{0}")]
    NoAdapter(String),
    /// The device could not be created.
    #[error("cannot create a device on adapter `{adapter}`: {source}")]
    Device {
        /// Adapter name.
        adapter: String,
        /// The wgpu error.
        source: wgpu::RequestDeviceError,
    },
    /// A size over what the device allows.
    #[error("{what} = {value} exceeds the device limit {limit} ({limit_name})")]
    OverLimit {
        /// What was asked for.
        what: String,
        /// The value.
        value: u64,
        /// The limit.
        limit: u64,
        /// The name of the wgpu limit.
        limit_name: &'static str,
    },
    /// A size over what an algorithm of this project handles (not a device limit).
    #[error("{what} = {value} exceeds {limit}, the most {why}")]
    OverCapacity {
        /// What was asked for.
        what: String,
        /// The value.
        value: u64,
        /// The largest value handled.
        limit: u64,
        /// Why, and what to do instead.
        why: &'static str,
    },
    /// A wgpu validation or out-of-memory error caught on the device, or a lost device.
    #[error("GPU error during {during}: {message}")]
    Runtime {
        /// What was being done.
        during: String,
        /// The wgpu message.
        message: String,
    },
    /// Mapping a buffer for readback failed.
    #[error("buffer readback failed: {0}")]
    Readback(String),
    /// A setting this device does not support; the message names what it supports.
    #[error("{0}")]
    Unsupported(String),
}

/// How to choose the adapter.
#[derive(Clone, Debug, Default)]
pub struct GpuOptions {
    /// A case-insensitive substring of the adapter name, or its index; `None` reads
    /// [`ADAPTER_ENV`], and failing that prefers a discrete GPU, then integrated, then others.
    pub adapter: Option<String>,
}

/// Optional features negotiated with the adapter.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Negotiated {
    /// Timestamp queries at pass boundaries (`TIMESTAMP_QUERY`).
    pub timestamps: bool,
    /// Timestamps written between passes (`TIMESTAMP_QUERY_INSIDE_ENCODERS`), for timing a span
    /// of passes with one pair ([`crate::GpuTimer::spans`]).
    pub encoder_timestamps: bool,
    /// Subgroup operations in compute shaders (`SUBGROUP`).
    pub subgroups: bool,
    /// Smallest and largest subgroup size the adapter reports.
    pub subgroup_size: (u32, u32),
    /// `@builtin(primitive_index)` in fragment shaders (`PRIMITIVE_INDEX`; on Vulkan the
    /// `geometryShader` feature): the visibility buffer's triangle ids.
    pub primitive_index: bool,
    /// 64-bit integers and their atomic min and max on storage buffers (`SHADER_INT64`,
    /// `SHADER_INT64_ATOMIC_MIN_MAX`): the compute visibility pass.
    pub int64_atomics: bool,
    /// Every 64-bit atomic on storage buffers, add and compare-exchange among them
    /// (`SHADER_INT64`, `SHADER_INT64_ATOMIC_ALL_OPS`): the hierarchy build's sums, one atomic
    /// an add (`manylights_gpu::hierarchy::Sums`).
    pub int64_atomic_add: bool,
}

/// A headless wgpu device and what was negotiated for it.
pub struct GpuContext {
    /// The adapter in use.
    pub adapter: wgpu::Adapter,
    /// The device.
    pub device: wgpu::Device,
    /// Its queue.
    pub queue: wgpu::Queue,
    /// Adapter name, driver, backend.
    pub info: wgpu::AdapterInfo,
    /// Optional features that were enabled.
    pub features: Negotiated,
    /// The limits in force (the adapter's own, not WebGPU's defaults).
    pub limits: wgpu::Limits,
    /// Loop iterations a shader invocation may run in all, where the driver stops loops short
    /// silently (see [`LLVMPIPE_LOOP_LIMIT`]); `None` where it does not.
    pub loop_limit: Option<u64>,
    errors: std::sync::Arc<std::sync::Mutex<Option<String>>>,
    /// When the open frame encoder was created (see [`GpuContext::encoder`]).
    encode_start: std::sync::Mutex<Option<std::time::Instant>>,
    /// CPU time spent recording frame encoders since the last [`GpuContext::take_encode_ms`].
    encode_total: std::sync::Mutex<std::time::Duration>,
}

impl fmt::Debug for GpuContext {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("GpuContext")
            .field("info", &self.info)
            .field("features", &self.features)
            .finish_non_exhaustive()
    }
}

fn is_llvmpipe(info: &wgpu::AdapterInfo) -> bool {
    info.name.contains("llvmpipe") || info.driver.contains("llvmpipe")
}

fn describe(i: usize, info: &wgpu::AdapterInfo) -> String {
    format!(
        "  [{i}] {} ({:?}, {:?}, driver {} {})",
        info.name, info.device_type, info.backend, info.driver, info.driver_info
    )
}

/// Mesa's llvmpipe (lavapipe) ends every loop of a shader invocation, silently, once the
/// invocation has run 65,535 loop iterations in all (`LP_MAX_TGSI_LOOP_ITERATIONS`, shared by
/// every loop of the shader). A per-pixel loop over more lights than that stops short; and a
/// loop behind a runtime condition that no invocation meets is entered all the same (its lanes
/// masked off) and counts an iteration each time, so a light's test in such a loop must hold
/// none (`crates/gpu/tests/loop_limit.rs` measures both).
pub const LLVMPIPE_LOOP_LIMIT: u64 = 65_535;

impl GpuContext {
    /// Opens a device on the chosen adapter with every optional feature it offers that the
    /// project uses, and the adapter's full limits.
    pub fn new(options: &GpuOptions) -> Result<Self, GpuError> {
        let instance = wgpu::Instance::new(wgpu::InstanceDescriptor {
            backends: wgpu::Backends::VULKAN,
            ..wgpu::InstanceDescriptor::new_without_display_handle_from_env()
        });
        let adapters = pollster::block_on(instance.enumerate_adapters(wgpu::Backends::VULKAN));
        let infos: Vec<wgpu::AdapterInfo> = adapters.iter().map(wgpu::Adapter::get_info).collect();
        let listing = || {
            if infos.is_empty() {
                "  (none: no Vulkan driver was found; on a machine without a GPU install Mesa's lavapipe with \
                 `apt-get install mesa-vulkan-drivers libvulkan1`, or run `bash scripts/ensure-vulkan.sh`)"
                    .to_owned()
            } else {
                infos
                    .iter()
                    .enumerate()
                    .map(|(i, a)| describe(i, a))
                    .collect::<Vec<_>>()
                    .join("\n")
            }
        };
        let wanted = options
            .adapter
            .clone()
            .or_else(|| std::env::var(ADAPTER_ENV).ok())
            .filter(|s| !s.is_empty());
        let index = match &wanted {
            Some(w) => {
                let lw = w.to_lowercase();
                let by_index = w.parse::<usize>().ok().filter(|&i| i < infos.len());
                by_index.or_else(|| infos.iter().position(|a| a.name.to_lowercase().contains(&lw))).ok_or_else(|| {
                    GpuError::NoAdapter(format!("no adapter matches `{w}` (from --adapter or {ADAPTER_ENV}); adapters found:\n{}", listing()))
                })?
            }
            None => {
                let rank = |t: wgpu::DeviceType| match t {
                    wgpu::DeviceType::DiscreteGpu => 0,
                    wgpu::DeviceType::IntegratedGpu => 1,
                    wgpu::DeviceType::VirtualGpu => 2,
                    wgpu::DeviceType::Cpu => 3,
                    wgpu::DeviceType::Other => 4,
                };
                (0..infos.len())
                    .min_by_key(|&i| rank(infos[i].device_type))
                    .ok_or_else(|| {
                        GpuError::NoAdapter(format!(
                            "no GPU adapter found; adapters found:\n{}",
                            listing()
                        ))
                    })?
            }
        };
        let adapter = adapters
            .into_iter()
            .nth(index)
            .expect("index comes from the same list");
        let info = infos[index].clone();
        let offered = adapter.features();
        let mut required = wgpu::Features::empty();
        for f in [
            wgpu::Features::TIMESTAMP_QUERY,
            wgpu::Features::TIMESTAMP_QUERY_INSIDE_ENCODERS,
            wgpu::Features::SUBGROUP,
            // Sample counts other than 1 and 4 (MSAA 2 and 8) where the adapter has them.
            wgpu::Features::TEXTURE_ADAPTER_SPECIFIC_FORMAT_FEATURES,
            // The visibility buffer's triangle ids.
            wgpu::Features::PRIMITIVE_INDEX,
            // The compute visibility pass's keys.
            wgpu::Features::SHADER_INT64,
            wgpu::Features::SHADER_INT64_ATOMIC_MIN_MAX,
            // The hierarchy build's sums.
            wgpu::Features::SHADER_INT64_ATOMIC_ALL_OPS,
            // Forward's and the reference's shading, which writes the shadow-ray counters,
            // depth-tested before it runs (`@early_depth_test(force)`; every Vulkan device).
            wgpu::Features::SHADER_EARLY_DEPTH_TEST,
        ] {
            if offered.contains(f) {
                required |= f;
            }
        }
        let limits = adapter.limits();
        let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
            label: Some("manylights"),
            required_features: required,
            required_limits: limits.clone(),
            ..Default::default()
        }))
        .map_err(|source| GpuError::Device {
            adapter: info.name.clone(),
            source,
        })?;
        // wgpu reports validation errors and device loss asynchronously; keep the first one and
        // turn it into an error at the next wait, instead of a panic inside wgpu's callback.
        let errors = std::sync::Arc::new(std::sync::Mutex::new(None::<String>));
        let sink = errors.clone();
        device.on_uncaptured_error(std::sync::Arc::new(move |e| {
            let mut first = sink
                .lock()
                .unwrap_or_else(std::sync::PoisonError::into_inner);
            first.get_or_insert_with(|| e.to_string());
        }));
        let lost = errors.clone();
        device.set_device_lost_callback(move |reason, message| {
            let mut first = lost
                .lock()
                .unwrap_or_else(std::sync::PoisonError::into_inner);
            first.get_or_insert_with(|| format!("device lost ({reason:?}): {message}"));
        });
        let features = Negotiated {
            timestamps: required.contains(wgpu::Features::TIMESTAMP_QUERY),
            encoder_timestamps: required.contains(
                wgpu::Features::TIMESTAMP_QUERY | wgpu::Features::TIMESTAMP_QUERY_INSIDE_ENCODERS,
            ),
            subgroups: required.contains(wgpu::Features::SUBGROUP),
            subgroup_size: (info.subgroup_min_size, info.subgroup_max_size),
            primitive_index: required.contains(wgpu::Features::PRIMITIVE_INDEX),
            int64_atomics: required.contains(
                wgpu::Features::SHADER_INT64 | wgpu::Features::SHADER_INT64_ATOMIC_MIN_MAX,
            ),
            int64_atomic_add: required.contains(
                wgpu::Features::SHADER_INT64 | wgpu::Features::SHADER_INT64_ATOMIC_ALL_OPS,
            ),
        };
        let loop_limit = is_llvmpipe(&info).then_some(LLVMPIPE_LOOP_LIMIT);
        Ok(Self {
            adapter,
            device,
            queue,
            info,
            features,
            limits,
            loop_limit,
            errors,
            encode_start: Default::default(),
            encode_total: Default::default(),
        })
    }

    /// One line naming the adapter, driver and negotiated features, for logs and results.
    pub fn summary(&self) -> String {
        format!(
            "{} ({:?}; driver {} {}; timestamps: {}; subgroups: {} [{}..{}]; 64-bit atomics: {})",
            self.info.name,
            self.info.backend,
            self.info.driver,
            self.info.driver_info,
            if self.features.timestamps {
                "yes"
            } else {
                "no"
            },
            if self.features.subgroups { "yes" } else { "no" },
            self.features.subgroup_size.0,
            self.features.subgroup_size.1,
            match (self.features.int64_atomic_add, self.features.int64_atomics) {
                (true, _) => "all",
                (false, true) => "min/max",
                (false, false) => "no",
            },
        )
    }

    /// Checks a render-target size against the device's texture limit.
    pub fn check_resolution(&self, width: u32, height: u32) -> Result<(), GpuError> {
        let limit = self.limits.max_texture_dimension_2d;
        for (what, v) in [("width", width), ("height", height)] {
            if v > limit {
                return Err(GpuError::OverLimit {
                    what: what.into(),
                    value: v.into(),
                    limit: limit.into(),
                    limit_name: "max_texture_dimension_2d",
                });
            }
        }
        Ok(())
    }

    /// The most lights per-pixel loops may visit under the driver's loop limit, where it has
    /// one: half of it, since the exact oracle loops over every light and then over a list.
    pub fn loop_light_limit(&self) -> Option<u64> {
        self.loop_limit.map(|l| l / 2)
    }

    /// Checks a light count against the driver's loop limit, where it has one: the exact
    /// oracle loops over every light and then over a list of up to every light, so each
    /// invocation may run twice the light count in iterations.
    pub fn check_loop_count(&self, what: &str, lights: u64) -> Result<(), GpuError> {
        match self.loop_light_limit() {
            Some(limit) if lights > limit => Err(GpuError::OverLimit {
                what: what.into(),
                value: lights,
                limit,
                limit_name: "llvmpipe's 65,535 loop iterations per shader invocation, which it \
                             enforces by ending loops early without an error; use a hardware GPU",
            }),
            _ => Ok(()),
        }
    }

    /// Checks a storage buffer size against the device's binding limit.
    pub fn check_storage(&self, what: &str, bytes: u64) -> Result<(), GpuError> {
        let limit = self
            .limits
            .max_storage_buffer_binding_size
            .min(self.limits.max_buffer_size);
        if bytes > limit {
            return Err(GpuError::OverLimit {
                what: what.into(),
                value: bytes,
                limit,
                limit_name: "max_storage_buffer_binding_size",
            });
        }
        Ok(())
    }

    /// A command encoder for frame work; the CPU time from here to its submission counts as
    /// encoding time ([`GpuContext::take_encode_ms`], the `cpu_ms_encode` of results).
    pub fn encoder(&self, label: &str) -> wgpu::CommandEncoder {
        *self
            .encode_start
            .lock()
            .unwrap_or_else(std::sync::PoisonError::into_inner) = Some(std::time::Instant::now());
        self.device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some(label) })
    }

    /// The MSAA sample counts the depth buffer can have on this device (1 and 4 everywhere,
    /// WebGPU's guarantee; 2, 8 and 16 where the adapter has them).
    pub fn msaa_counts(&self) -> Vec<u32> {
        self.msaa_counts_of(&[crate::prepass::DEPTH_FORMAT])
    }

    /// The MSAA sample counts every one of `formats` can have on this device (a float colour
    /// format must also resolve at that count). Without adapter-specific format features, WebGPU's
    /// guarantee: 1, and 4 for formats that are multisampled there.
    pub fn msaa_counts_of(&self, formats: &[wgpu::TextureFormat]) -> Vec<u32> {
        let specific = self
            .device
            .features()
            .contains(wgpu::Features::TEXTURE_ADAPTER_SPECIFIC_FORMAT_FEATURES);
        [1, 2, 4, 8, 16]
            .into_iter()
            .filter(|&n| {
                formats.iter().all(|&format| {
                    let flags = if specific {
                        self.adapter.get_texture_format_features(format).flags
                    } else {
                        format
                            .guaranteed_format_features(self.device.features())
                            .flags
                    };
                    // Integer formats never resolve (a G-buffer's material index is not).
                    let integer = matches!(
                        format.sample_type(None, None),
                        Some(wgpu::TextureSampleType::Uint | wgpu::TextureSampleType::Sint)
                    );
                    let resolves = format.is_depth_stencil_format()
                        || integer
                        || n == 1
                        || flags.contains(wgpu::TextureFormatFeatureFlags::MULTISAMPLE_RESOLVE);
                    n == 1 || (flags.sample_count_supported(n) && resolves)
                })
            })
            .collect()
    }

    /// Checks an MSAA sample count against [`GpuContext::msaa_counts`]: an error naming the
    /// counts this device supports.
    pub fn check_msaa(&self, samples: u32) -> Result<(), GpuError> {
        self.check_msaa_of(samples, &[crate::prepass::DEPTH_FORMAT])
    }

    /// Checks an MSAA sample count against [`GpuContext::msaa_counts_of`] `formats` (the depth
    /// buffer and the colour targets of a pass): an error naming the counts this device
    /// supports for them.
    pub fn check_msaa_of(
        &self,
        samples: u32,
        formats: &[wgpu::TextureFormat],
    ) -> Result<(), GpuError> {
        let counts = self.msaa_counts_of(formats);
        if counts.contains(&samples) {
            return Ok(());
        }
        Err(GpuError::Unsupported(format!(
            "MSAA with {samples} samples: {} supports {} (for {:?})",
            self.info.name,
            counts
                .iter()
                .map(u32::to_string)
                .collect::<Vec<_>>()
                .join(", "),
            formats
        )))
    }

    /// CPU milliseconds spent recording frame encoders since the last call.
    pub fn take_encode_ms(&self) -> f64 {
        let mut t = self
            .encode_total
            .lock()
            .unwrap_or_else(std::sync::PoisonError::into_inner);
        std::mem::take(&mut *t).as_secs_f64() * 1e3
    }

    /// Submits, waits for the queue to drain, and turns a lost device into an error.
    pub fn submit_and_wait(
        &self,
        encoder: wgpu::CommandEncoder,
        during: &str,
    ) -> Result<(), GpuError> {
        if let Some(start) = self
            .encode_start
            .lock()
            .unwrap_or_else(std::sync::PoisonError::into_inner)
            .take()
        {
            *self
                .encode_total
                .lock()
                .unwrap_or_else(std::sync::PoisonError::into_inner) += start.elapsed();
        }
        let index = self.queue.submit([encoder.finish()]);
        let waited = std::time::Instant::now();
        let polled = self
            .device
            .poll(wgpu::PollType::Wait {
                submission_index: Some(index),
                timeout: None,
            })
            .map_err(|e| {
                // A recorded error (a lost device, say) is the cause; the failed wait follows.
                // wgpu reports the loss to its callback on a poll.
                let _ = self.device.poll(wgpu::PollType::Poll);
                let first = self
                    .errors
                    .lock()
                    .unwrap_or_else(std::sync::PoisonError::into_inner)
                    .take();
                GpuError::Runtime {
                    during: during.into(),
                    message: first.map_or_else(|| e.to_string(), |f| format!("{f} (then: {e})")),
                }
            });
        tracing::debug!(
            during,
            wait_ms = waited.elapsed().as_secs_f64() * 1e3,
            "GPU submission done"
        );
        polled?;
        self.check(during)
    }

    /// Returns the first asynchronous wgpu error (validation, out of memory, device lost) seen
    /// since the device was created, if any.
    pub fn check(&self, during: &str) -> Result<(), GpuError> {
        let first = self
            .errors
            .lock()
            .unwrap_or_else(std::sync::PoisonError::into_inner)
            .take();
        match first {
            Some(message) => Err(GpuError::Runtime {
                during: during.into(),
                message,
            }),
            None => Ok(()),
        }
    }
}

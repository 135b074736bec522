//! The Embree backend: safe, owning wrappers over `embree-sys` and a
//! [`Tracer`] built on them.
//!
//! # Ownership
//! [`Device`], [`Scene`] and [`Geometry`] each own one Embree reference and
//! release it on `Drop`. Embree reference-counts its objects internally (a
//! scene keeps its geometries, an instance keeps its instanced scene, every
//! object keeps its device), so handles may be dropped in any order. Rust-side
//! state the device needs (the error slot its callback writes to) sits behind
//! an `Arc` that every child handle holds, so it outlives all of them.
//!
//! # Scene layout
//! One Embree scene per [`SceneGeometry`]. A mesh placed by a single instance
//! is attached directly to the top-level scene as a triangle geometry (its
//! vertices transformed to world space when the transform is not the
//! identity). A mesh placed by two or more instances is stored once in its own
//! scene and placed by Embree *instance* geometries (Debian's build has one
//! instance level). Either way the top-level geometry id is the
//! [`SceneGeometry`] instance index, so hits report `(instance, prim)` in the
//! crate's numbering.
//!
//! # Queries
//! The query follows the batch's [`Coherence`] ([`RayMode::ByCoherence`],
//! the default). Coherent batches go through Embree's packet API at the
//! width chosen at run time ([`Device::native_packet_width`]: 8 on AVX2 and
//! AVX-512, else 16, else 4), with Embree's coherent flag; packets are formed
//! from consecutive rays of the batch, so callers put coherent rays (a 4×2
//! or 8×1 pixel tile) next to each other. Incoherent batches go through
//! Embree 3's stream API (`rtcIntersect1M` / `rtcOccluded1M`), or one ray at
//! a time (`rtcIntersect1` / `rtcOccluded1`) on Embree 4, which has no
//! stream API. Fixed modes ([`RayMode::Single`], [`RayMode::Packet`],
//! [`RayMode::Stream`]) exist for comparisons; all give the same hits bit
//! for bit (tests/backends.rs).
//!
//! # Embree 3 and 4
//! `embree-sys` binds whichever is installed (Debian 12: 3.13, Debian 13:
//! 4.3) and sets `cfg(embree4)` for Embree 4. The differences stay in this
//! module: the per-query arguments (Embree 3's `RTCIntersectContext` before
//! the rays, Embree 4's `RTCIntersectArguments` / `RTCOccludedArguments`
//! after them: `QueryArgs`, `intersect_call!`, `occluded_call!`) and the
//! stream API, which Embree 4 dropped ([`STREAM_API`]). Everything else —
//! devices, scenes, buffers, instances, ray and hit layouts as used here —
//! is the same in both.

use std::ffi::{CStr, c_char, c_void};
use std::marker::PhantomData;
use std::sync::{Arc, Mutex};

use embree_sys as raw;
use glam::{Affine3A, Mat3A, Vec3};

use super::{Coherence, Hit, Ray, Tracer, Watertight};
use crate::error::{Error, Result};
use crate::geometry::SceneGeometry;

/// The calling thread's SSE control and status register (MXCSR), for checks
/// that Embree calls leave it as they found it. x86-64 only.
#[cfg(target_arch = "x86_64")]
pub fn mxcsr() -> u32 {
    let mut csr: u32 = 0;
    // SAFETY: `stmxcsr` stores the 32-bit MXCSR register to the given
    // address, which points to a live local `u32`.
    unsafe {
        std::arch::asm!("stmxcsr [{}]", in(reg) &mut csr, options(nostack, preserves_flags));
    }
    csr
}

/// Sets flush-to-zero and denormals-are-zero in this thread's MXCSR for as
/// long as it lives, as Embree recommends for performance, and restores the
/// previous setting on drop (also when unwinding). One guard spans each batch
/// of Embree calls, so the flags never leak into the caller's own maths.
/// No-op on other architectures.
#[must_use]
struct FlushDenormals {
    #[cfg(target_arch = "x86_64")]
    saved: u32,
}

#[cfg(target_arch = "x86_64")]
fn set_mxcsr(csr: u32) {
    // SAFETY: `ldmxcsr` loads MXCSR from a live local `u32`. Callers pass
    // either a value read from MXCSR or one with only FTZ/DAZ added to it,
    // so no reserved bit is ever set (which would fault). Changing the
    // floating-point mode is what this is for; Rust code that runs meanwhile
    // (our own ray packing) does not depend on denormals.
    unsafe {
        std::arch::asm!("ldmxcsr [{}]", in(reg) &csr, options(nostack, readonly, preserves_flags));
    }
}

impl FlushDenormals {
    #[cfg(target_arch = "x86_64")]
    const FTZ_DAZ: u32 = (1 << 15) | (1 << 6);

    fn new() -> Self {
        #[cfg(target_arch = "x86_64")]
        {
            let saved = mxcsr();
            if saved & Self::FTZ_DAZ != Self::FTZ_DAZ {
                set_mxcsr(saved | Self::FTZ_DAZ);
            }
            FlushDenormals { saved }
        }
        #[cfg(not(target_arch = "x86_64"))]
        FlushDenormals {}
    }
}

impl Drop for FlushDenormals {
    fn drop(&mut self) {
        #[cfg(target_arch = "x86_64")]
        if mxcsr() != self.saved {
            set_mxcsr(self.saved);
        }
    }
}

/// Rust-side state of a device: the handle and the slot where the error
/// callback records the first error message since the last check.
struct DeviceInner {
    raw: raw::RTCDevice,
    error: Box<Mutex<Option<String>>>,
    config: String,
}

// SAFETY: Embree devices are thread-safe (the API may be called from any
// thread); the error slot is a Mutex.
unsafe impl Send for DeviceInner {}
// SAFETY: as above.
unsafe impl Sync for DeviceInner {}

impl Drop for DeviceInner {
    fn drop(&mut self) {
        // SAFETY: `raw` is a valid device we hold one reference to. The
        // callback is removed first so that it can never see a dangling
        // `error` pointer, should Embree keep the device alive longer.
        unsafe {
            raw::rtcSetDeviceErrorFunction(self.raw, None, std::ptr::null_mut());
            raw::rtcReleaseDevice(self.raw);
        }
    }
}

/// Called by Embree on an error in any thread; records the first message.
unsafe extern "C" fn error_callback(user: *mut c_void, code: raw::RTCError, msg: *const c_char) {
    let _ = std::panic::catch_unwind(|| {
        let text = if msg.is_null() {
            String::new()
        } else {
            // SAFETY: Embree passes a NUL-terminated message valid for the
            // duration of the call.
            unsafe { CStr::from_ptr(msg) }
                .to_string_lossy()
                .into_owned()
        };
        // SAFETY: `user` is the `Mutex` in `DeviceInner::error`, boxed (stable
        // address) and alive until the callback is unset in `Drop`.
        let slot = unsafe { &*(user as *const Mutex<Option<String>>) };
        let mut g = slot.lock().unwrap_or_else(|e| e.into_inner());
        if g.is_none() {
            *g = Some(format!("{} ({text})", error_name(code)));
        }
    });
}

fn error_name(code: raw::RTCError) -> &'static str {
    match code {
        raw::RTC_ERROR_NONE => "no error",
        raw::RTC_ERROR_INVALID_ARGUMENT => "invalid argument",
        raw::RTC_ERROR_INVALID_OPERATION => "invalid operation",
        raw::RTC_ERROR_OUT_OF_MEMORY => "out of memory",
        raw::RTC_ERROR_UNSUPPORTED_CPU => "unsupported CPU",
        raw::RTC_ERROR_CANCELLED => "cancelled",
        _ => "unknown error",
    }
}

/// How to create a [`Device`].
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct DeviceConfig {
    /// Threads Embree's builder may use (`threads=N`); `None` for rayon's
    /// thread count where the device is created
    /// ([`rayon::current_num_threads`]: the global pool, which the CLI sizes
    /// from `--threads`, or the pool the call runs in).
    pub threads: Option<usize>,
    /// Embree's `verbose=N` (0: quiet). Level 1 prints the configuration,
    /// including the thread count, to standard output.
    pub verbose: u32,
}

impl DeviceConfig {
    /// The configuration string passed to `rtcNewDevice`, e.g. `"threads=2"`.
    pub fn to_config_string(&self) -> String {
        let threads = self
            .threads
            .unwrap_or_else(rayon::current_num_threads)
            .max(1);
        let mut s = format!("threads={threads}");
        if self.verbose > 0 {
            s.push_str(&format!(",verbose={}", self.verbose));
        }
        s
    }
}

/// An Embree device (the library instance: thread pool, ISA choice).
#[derive(Clone)]
pub struct Device(Arc<DeviceInner>);

impl Device {
    /// Creates a device whose builder uses rayon's thread count
    /// ([`DeviceConfig::default`]).
    pub fn new() -> Result<Self> {
        Self::with_config(&DeviceConfig::default())
    }

    /// Creates a device whose builder uses `threads` threads.
    pub fn with_threads(threads: usize) -> Result<Self> {
        Self::with_config(&DeviceConfig {
            threads: Some(threads),
            ..DeviceConfig::default()
        })
    }

    /// Creates a device configured by `config`.
    pub fn with_config(config: &DeviceConfig) -> Result<Self> {
        let text = config.to_config_string();
        let c_text =
            std::ffi::CString::new(text.clone()).expect("the configuration string has no NUL byte");
        // SAFETY: `c_text` is a NUL-terminated string that lives across the
        // call (Embree parses it during the call and keeps no pointer).
        let dev = unsafe { raw::rtcNewDevice(c_text.as_ptr()) };
        if dev.is_null() {
            // SAFETY: querying the error of a NULL device returns the error
            // of the last failed device creation on this thread.
            let code = unsafe { raw::rtcGetDeviceError(std::ptr::null_mut()) };
            return Err(Error::Embree(format!(
                "cannot create a device (`{text}`): {}",
                error_name(code)
            )));
        }
        let inner = DeviceInner {
            raw: dev,
            error: Box::new(Mutex::new(None)),
            config: text,
        };
        let user = &*inner.error as *const Mutex<Option<String>> as *mut c_void;
        // SAFETY: `dev` is valid; `user` points to the boxed Mutex, which
        // lives as long as `inner` (the callback is unset before release).
        unsafe { raw::rtcSetDeviceErrorFunction(dev, Some(error_callback), user) };
        Ok(Device(Arc::new(inner)))
    }

    /// The configuration string the device was created with, e.g.
    /// `"threads=2"`.
    pub fn config(&self) -> &str {
        &self.0.config
    }

    fn same_as(&self, other: &Device) -> bool {
        Arc::ptr_eq(&self.0, &other.0)
    }

    /// The raw handle (valid while `self` lives).
    pub fn as_raw(&self) -> raw::RTCDevice {
        self.0.raw
    }

    /// Takes the first error reported since the last check, as an `Err`.
    pub fn check(&self) -> Result<()> {
        let mut g = self.0.error.lock().unwrap_or_else(|e| e.into_inner());
        match g.take() {
            Some(m) => Err(Error::Embree(m)),
            None => Ok(()),
        }
    }

    /// Whether the library supports `width`-wide packets natively (4, 8, 16).
    pub fn supports_packet_width(&self, width: usize) -> bool {
        let prop = match width {
            4 => raw::RTC_DEVICE_PROPERTY_NATIVE_RAY4_SUPPORTED,
            8 => raw::RTC_DEVICE_PROPERTY_NATIVE_RAY8_SUPPORTED,
            16 => raw::RTC_DEVICE_PROPERTY_NATIVE_RAY16_SUPPORTED,
            _ => return false,
        };
        // SAFETY: valid device, valid property id.
        unsafe { raw::rtcGetDeviceProperty(self.0.raw, prop) != 0 }
    }

    /// The packet width to use by default: 8 where supported natively
    /// (AVX2 and AVX-512 builds), else 16, else 4.
    ///
    /// Width 16 is not preferred on AVX-512 machines: Debian's Embree 3.13.5
    /// was seen to loop forever in `rtcOccluded16` with the coherent flag on
    /// scattered rays (AMD Zen 4), and 8-wide packets measured as fast on
    /// primary rays. Width 16 stays available through [`RayMode::Packet`]
    /// (its occlusion queries then never set the coherent flag).
    pub fn native_packet_width(&self) -> usize {
        [8, 16, 4]
            .into_iter()
            .find(|&w| self.supports_packet_width(w))
            .unwrap_or(4)
    }

    /// The library's version, e.g. `"3.13.5"`.
    pub fn version(&self) -> String {
        let get = |p| {
            // SAFETY: valid device, valid property id.
            unsafe { raw::rtcGetDeviceProperty(self.0.raw, p) }
        };
        format!(
            "{}.{}.{}",
            get(raw::RTC_DEVICE_PROPERTY_VERSION_MAJOR),
            get(raw::RTC_DEVICE_PROPERTY_VERSION_MINOR),
            get(raw::RTC_DEVICE_PROPERTY_VERSION_PATCH)
        )
    }
}

/// Memory a geometry or scene keeps alive because Embree reads it: owned
/// vertex buffers and instanced scenes (with what they keep in turn).
type KeepAlive<'a> = Arc<dyn Send + Sync + 'a>;

/// An Embree scene (an acceleration structure over geometries).
///
/// `'a` bounds the vertex memory its geometries borrow
/// ([`Geometry::triangles`]): the scene cannot outlive it, so dropping a
/// borrowed [`VertexBuffer`] before the scene does not compile. Memory
/// handed over in an `Arc` ([`Geometry::triangles_shared`], instanced
/// scenes) is kept alive by the scene itself.
pub struct Scene<'a> {
    raw: raw::RTCScene,
    device: Device,
    keep: Vec<KeepAlive<'a>>,
    committed: bool,
    _borrows: PhantomData<&'a VertexBuffer>,
}

// SAFETY: Embree scenes may be used from any thread; after `commit` they are
// immutable and queries are thread-safe. Mutation goes through `&mut self`.
// What `keep` holds is itself `Send + Sync`.
unsafe impl Send for Scene<'_> {}
// SAFETY: as above: `&Scene` only allows queries.
unsafe impl Sync for Scene<'_> {}

impl Drop for Scene<'_> {
    fn drop(&mut self) {
        // SAFETY: we own one reference to a valid scene. Embree may keep the
        // scene alive longer (an instance holds a reference), but only
        // through handles that also hold `keep` (see `Geometry::instance`).
        unsafe { raw::rtcReleaseScene(self.raw) }
    }
}

impl<'a> Scene<'a> {
    /// A new empty scene on `device`; `watertight` selects Embree's robust
    /// triangle and box tests (`RTC_SCENE_FLAG_ROBUST`).
    pub fn new(device: &Device, watertight: Watertight) -> Result<Self> {
        // SAFETY: valid device.
        let s = unsafe { raw::rtcNewScene(device.as_raw()) };
        device.check()?;
        if s.is_null() {
            return Err(Error::Embree("cannot create a scene".into()));
        }
        let flags = match watertight {
            Watertight::Yes => raw::RTC_SCENE_FLAG_ROBUST,
            Watertight::No => raw::RTC_SCENE_FLAG_NONE,
        };
        // SAFETY: valid, uncommitted scene; a defined flag.
        unsafe { raw::rtcSetSceneFlags(s, flags) };
        if let Err(e) = device.check() {
            // SAFETY: we own the only reference to `s`.
            unsafe { raw::rtcReleaseScene(s) };
            return Err(e);
        }
        Ok(Scene {
            raw: s,
            device: device.clone(),
            keep: Vec::new(),
            committed: false,
            _borrows: PhantomData,
        })
    }

    /// Attaches `geom` under the id `id`. The scene keeps its own Embree
    /// reference to the geometry and whatever memory the geometry keeps
    /// alive, so `geom` may be dropped afterwards.
    pub fn attach(&mut self, geom: &Geometry<'a>, id: u32) -> Result<()> {
        if !self.device.same_as(&geom.device) {
            return Err(Error::invalid(
                "geometry",
                "attached to a scene of another Embree device",
            ));
        }
        // SAFETY: valid scene and committed geometry of the same device
        // (checked above). The memory the geometry reads is either borrowed
        // for `'a`, which the scene cannot outlive, or kept in `keep`.
        unsafe { raw::rtcAttachGeometryByID(self.raw, geom.raw, id) };
        self.device.check()?;
        self.keep.extend(geom.keep.iter().cloned());
        self.committed = false;
        Ok(())
    }

    /// Builds the acceleration structure.
    pub fn commit(&mut self) -> Result<()> {
        // SAFETY: valid scene; every geometry's memory is alive (see
        // `attach`).
        unsafe { raw::rtcCommitScene(self.raw) };
        self.device.check()?;
        self.committed = true;
        Ok(())
    }

    /// Whether the scene was committed since the last change.
    pub fn is_committed(&self) -> bool {
        self.committed
    }

    /// The raw handle (valid while `self` lives).
    pub fn as_raw(&self) -> raw::RTCScene {
        self.raw
    }
}

/// An Embree geometry (a triangle mesh or an instance).
///
/// `'a` bounds the vertex memory it borrows ([`Geometry::triangles`]);
/// `Geometry<'static>` borrows nothing.
pub struct Geometry<'a> {
    raw: raw::RTCGeometry,
    device: Device,
    keep: Option<KeepAlive<'a>>,
    _borrows: PhantomData<&'a VertexBuffer>,
}

// SAFETY: Embree geometries may be used from any thread; mutation happens
// only while building (inside the constructors). What `keep` holds is
// `Send + Sync`.
unsafe impl Send for Geometry<'_> {}
// SAFETY: as above: `&Geometry` only allows attaching it to a scene.
unsafe impl Sync for Geometry<'_> {}

impl Drop for Geometry<'_> {
    fn drop(&mut self) {
        // SAFETY: we own one reference to a valid geometry.
        unsafe { raw::rtcReleaseGeometry(self.raw) }
    }
}

/// Vertex storage for a shared Embree buffer: `xyz` per vertex plus one float
/// of padding at the end (Embree reads 16 bytes for the last vertex).
///
/// Immutable once made: Embree reads it in place while traced.
pub struct VertexBuffer(Vec<f32>);

impl VertexBuffer {
    /// Packs `points` with the trailing pad float.
    pub fn new(points: impl ExactSizeIterator<Item = Vec3>) -> Self {
        let mut v = Vec::with_capacity(points.len() * 3 + 1);
        for p in points {
            v.extend_from_slice(&[p.x, p.y, p.z]);
        }
        v.push(0.0);
        VertexBuffer(v)
    }

    /// The number of vertices.
    pub fn count(&self) -> usize {
        (self.0.len() - 1) / 3
    }
}

impl<'a> Geometry<'a> {
    /// A triangle mesh over `vertices` (borrowed: Embree reads it in place,
    /// so neither this geometry nor any scene it is attached to may outlive
    /// it — enforced by `'a`) and `indices` (copied into a new Embree
    /// buffer).
    ///
    /// Indices are validated against the vertex count.
    ///
    /// ```
    /// use irsig::trace::Watertight;
    /// use irsig::trace::embree::{Device, Geometry, Scene, VertexBuffer};
    /// use glam::Vec3;
    ///
    /// let device = Device::new()?;
    /// let vb = VertexBuffer::new([Vec3::ZERO, Vec3::X, Vec3::Y].into_iter());
    /// let mut scene = Scene::new(&device, Watertight::Yes)?;
    /// let g = Geometry::triangles(&device, &vb, &[[0, 1, 2]])?;
    /// scene.attach(&g, 0)?;
    /// drop(g); // the scene keeps the geometry, but not the buffer:
    /// scene.commit()?;
    /// drop(scene); // so the buffer must outlive the scene.
    /// drop(vb);
    /// # Ok::<(), irsig::Error>(())
    /// ```
    ///
    /// Dropping the buffer before the scene's last use does not compile
    /// (E0505: move out of `vb` while borrowed):
    ///
    /// ```compile_fail,E0505
    /// use irsig::trace::Watertight;
    /// use irsig::trace::embree::{Device, Geometry, Scene, VertexBuffer};
    /// use glam::Vec3;
    ///
    /// let device = Device::new()?;
    /// let vb = VertexBuffer::new([Vec3::ZERO, Vec3::X, Vec3::Y].into_iter());
    /// let mut scene = Scene::new(&device, Watertight::Yes)?;
    /// let g = Geometry::triangles(&device, &vb, &[[0, 1, 2]])?;
    /// scene.attach(&g, 0)?;
    /// drop(g);
    /// drop(vb);
    /// scene.commit()?; // Embree would read the freed vertices here
    /// # Ok::<(), irsig::Error>(())
    /// ```
    pub fn triangles(
        device: &Device,
        vertices: &'a VertexBuffer,
        indices: &[[u32; 3]],
    ) -> Result<Self> {
        Self::new_triangles(device, vertices, indices, None)
    }

    /// A triangle mesh over `vertices`, which the geometry (and every scene
    /// it is attached to) keeps alive; otherwise as [`Geometry::triangles`].
    pub fn triangles_shared(
        device: &Device,
        vertices: Arc<VertexBuffer>,
        indices: &[[u32; 3]],
    ) -> Result<Geometry<'static>> {
        let vb: *const VertexBuffer = Arc::as_ptr(&vertices);
        // SAFETY: `vb` points into `vertices`, which the returned geometry
        // keeps alive (its `keep`) as long as Embree may read it.
        Geometry::new_triangles(
            device,
            unsafe { &*vb },
            indices,
            Some(vertices as KeepAlive<'static>),
        )
    }

    fn new_triangles(
        device: &Device,
        vertices: &'a VertexBuffer,
        indices: &[[u32; 3]],
        keep: Option<KeepAlive<'a>>,
    ) -> Result<Self> {
        let nv = vertices.count();
        if let Some((i, t)) = indices
            .iter()
            .enumerate()
            .find(|(_, t)| t.iter().any(|&k| k as usize >= nv))
        {
            return Err(Error::invalid(
                format!("triangle {i}"),
                format!("vertex index in {t:?} out of range (mesh has {nv} vertices)"),
            ));
        }
        // SAFETY: valid device and geometry type.
        let g = unsafe { raw::rtcNewGeometry(device.as_raw(), raw::RTC_GEOMETRY_TYPE_TRIANGLE) };
        device.check()?;
        let geom = Geometry {
            raw: g,
            device: device.clone(),
            keep,
            _borrows: PhantomData,
        };
        // SAFETY: `vertices.0` holds `nv` packed float3 plus one pad float, so
        // Embree's 16-byte loads stay in bounds. It outlives the geometry and
        // every scene the geometry is attached to: it is borrowed for `'a`,
        // which bounds both (for `triangles_shared`, `keep` holds it).
        unsafe {
            raw::rtcSetSharedGeometryBuffer(
                g,
                raw::RTC_BUFFER_TYPE_VERTEX,
                0,
                raw::RTC_FORMAT_FLOAT3,
                vertices.0.as_ptr() as *const c_void,
                0,
                12,
                nv,
            )
        };
        device.check()?;
        // SAFETY: Embree allocates `indices.len()` items of 12 bytes and
        // returns a pointer to them (or NULL on error, checked below).
        let ib = unsafe {
            raw::rtcSetNewGeometryBuffer(
                g,
                raw::RTC_BUFFER_TYPE_INDEX,
                0,
                raw::RTC_FORMAT_UINT3,
                12,
                indices.len(),
            )
        };
        device.check()?;
        if ib.is_null() && !indices.is_empty() {
            return Err(Error::Embree("cannot allocate an index buffer".into()));
        }
        if !indices.is_empty() {
            // SAFETY: `ib` points to `indices.len() * 12` writable bytes and
            // `[u32; 3]` is 12 bytes; the regions do not overlap.
            unsafe {
                std::ptr::copy_nonoverlapping(
                    indices.as_ptr() as *const u8,
                    ib as *mut u8,
                    std::mem::size_of_val(indices),
                )
            };
        }
        // SAFETY: valid geometry with its buffers set.
        unsafe { raw::rtcCommitGeometry(g) };
        device.check()?;
        Ok(geom)
    }

    /// An instance of the committed `scene`, placed by `world_from_object`.
    /// The instance keeps the scene (and the memory it keeps) alive.
    pub fn instance(
        device: &Device,
        scene: &Arc<Scene<'a>>,
        world_from_object: &Affine3A,
    ) -> Result<Self> {
        if !scene.committed {
            return Err(Error::invalid(
                "instanced scene",
                "not committed (call Scene::commit first)",
            ));
        }
        if !device.same_as(&scene.device) {
            return Err(Error::invalid(
                "instanced scene",
                "belongs to another Embree device",
            ));
        }
        // SAFETY: valid device and geometry type.
        let g = unsafe { raw::rtcNewGeometry(device.as_raw(), raw::RTC_GEOMETRY_TYPE_INSTANCE) };
        device.check()?;
        let geom = Geometry {
            raw: g,
            device: device.clone(),
            keep: Some(scene.clone() as KeepAlive<'a>),
            _borrows: PhantomData,
        };
        let m = world_from_object.matrix3;
        let t = world_from_object.translation;
        // Column-major 3×4: the three basis columns, then the translation.
        let xfm: [f32; 12] = [
            m.x_axis.x, m.x_axis.y, m.x_axis.z, m.y_axis.x, m.y_axis.y, m.y_axis.z, m.z_axis.x,
            m.z_axis.y, m.z_axis.z, t.x, t.y, t.z,
        ];
        // SAFETY: valid instance geometry and a committed scene of the same
        // device (checked above; the instance keeps both an Embree reference
        // to it and, in `keep`, the Rust handle with the memory it reads);
        // `xfm` holds 12 floats in the declared format and is copied by
        // Embree.
        unsafe {
            raw::rtcSetGeometryInstancedScene(g, scene.raw);
            raw::rtcSetGeometryTransform(
                g,
                0,
                raw::RTC_FORMAT_FLOAT3X4_COLUMN_MAJOR,
                xfm.as_ptr() as *const c_void,
            );
            raw::rtcCommitGeometry(g);
        }
        geom.device.check()?;
        Ok(geom)
    }
}

/// The per-batch query arguments, where Embree 3 and 4 differ: Embree 3
/// passes an `RTCIntersectContext` (holding the coherence flag) to every
/// query; Embree 4 passes `RTCIntersectArguments` / `RTCOccludedArguments`
/// (holding the flag; the ray-query context is optional and not needed
/// here) after the rays.
#[cfg(not(embree4))]
struct QueryArgs(raw::RTCIntersectContext);

#[cfg(embree4)]
struct QueryArgs {
    intersect: raw::RTCIntersectArguments,
    occluded: raw::RTCOccludedArguments,
}

impl QueryArgs {
    #[cfg(not(embree4))]
    fn new(coherence: Coherence) -> Self {
        let mut ctx = raw::RTCIntersectContext::default();
        // SAFETY: `ctx` is a valid, writable RTCIntersectContext.
        unsafe { raw::rtcInitIntersectContext(&mut ctx) };
        if coherence == Coherence::Coherent {
            ctx.flags = raw::RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
        }
        QueryArgs(ctx)
    }

    #[cfg(embree4)]
    fn new(coherence: Coherence) -> Self {
        let mut intersect = raw::RTCIntersectArguments::default();
        let mut occluded = raw::RTCOccludedArguments::default();
        // SAFETY: both point to valid, writable argument structures.
        unsafe {
            raw::rtcInitIntersectArguments(&mut intersect);
            raw::rtcInitOccludedArguments(&mut occluded);
        }
        if coherence == Coherence::Coherent {
            intersect.flags = raw::RTC_RAY_QUERY_FLAG_COHERENT;
            occluded.flags = raw::RTC_RAY_QUERY_FLAG_COHERENT;
        }
        QueryArgs {
            intersect,
            occluded,
        }
    }
}

/// Calls an Embree intersect function in the installed version's argument
/// order: `intersect_call!(single rtcIntersect1, scene, &mut QueryArgs,
/// rayhit)` or `intersect_call!(packet rtcIntersect8, valid, scene, args,
/// rayhit)`. Expands to an unsafe call.
#[cfg(not(embree4))]
macro_rules! intersect_call {
    (single $f:path, $scene:expr, $args:expr, $r:expr) => {
        $f($scene, &mut ($args).0, $r)
    };
    (packet $f:path, $valid:expr, $scene:expr, $args:expr, $r:expr) => {
        $f($valid, $scene, &mut ($args).0, $r)
    };
}
#[cfg(embree4)]
macro_rules! intersect_call {
    (single $f:path, $scene:expr, $args:expr, $r:expr) => {
        $f($scene, $r, &mut ($args).intersect)
    };
    (packet $f:path, $valid:expr, $scene:expr, $args:expr, $r:expr) => {
        $f($valid, $scene, $r, &mut ($args).intersect)
    };
}

/// As [`intersect_call!`] for the occlusion functions (`rtcOccluded*`).
#[cfg(not(embree4))]
macro_rules! occluded_call {
    (single $f:path, $scene:expr, $args:expr, $r:expr) => {
        $f($scene, &mut ($args).0, $r)
    };
    (packet $f:path, $valid:expr, $scene:expr, $args:expr, $r:expr) => {
        $f($valid, $scene, &mut ($args).0, $r)
    };
}
#[cfg(embree4)]
macro_rules! occluded_call {
    (single $f:path, $scene:expr, $args:expr, $r:expr) => {
        $f($scene, $r, &mut ($args).occluded)
    };
    (packet $f:path, $valid:expr, $scene:expr, $args:expr, $r:expr) => {
        $f($valid, $scene, $r, &mut ($args).occluded)
    };
}

/// Ray-packet valid mask, aligned as Embree requires for every width
/// (16/32/64 bytes for 4/8/16 lanes).
#[repr(C, align(64))]
struct Valid<const W: usize>([i32; W]);

/// How an [`EmbreeTracer`] feeds rays to Embree.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum RayMode {
    /// One ray at a time (`rtcIntersect1` / `rtcOccluded1`).
    Single,
    /// Packets of this width (4, 8 or 16: `rtcIntersect4/8/16`).
    Packet(usize),
    /// Embree 3's stream API over each batch (`rtcIntersect1M` /
    /// `rtcOccluded1M`); Embree 4 has none (an error there).
    Stream,
    /// Chosen per batch from its [`Coherence`] (the default,
    /// [`EmbreeTracer::new`]): packets of this width for coherent batches
    /// (camera rows and tiles, with the coherent flag) and incoherent ones
    /// (a facet's hemisphere rays, secondary rays; no flag); for scattered
    /// ones (unrelated origins and directions) the stream API on Embree 3
    /// and single rays on Embree 4, which has no stream API. Measured with
    /// `irsig bench modes --watertight no` (Embree 3.13.5, 1 M triangles, 2 threads):
    /// on scattered rays the stream beat single rays by 5–40 % and packets
    /// by 0–60 %; packets beat single rays about 2× on camera tiles.
    ByCoherence(usize),
}

impl RayMode {
    /// The mode used for a batch of the given coherence.
    pub fn for_batch(self, coherence: Coherence) -> RayMode {
        match (self, coherence) {
            (RayMode::ByCoherence(w), Coherence::Coherent) => RayMode::Packet(w),
            (RayMode::ByCoherence(w), Coherence::Incoherent) => RayMode::Packet(w),
            (RayMode::ByCoherence(_), Coherence::Scattered) if STREAM_API => RayMode::Stream,
            (RayMode::ByCoherence(_), Coherence::Scattered) => RayMode::Single,
            (m, _) => m,
        }
    }
}

/// Which meshes placed by two or more instances are traced through Embree
/// instancing (a two-level BVH: the mesh stored once, each ray transformed
/// into it) rather than flattened (every placement's triangles in world
/// space in the one top-level BVH, as obvhs always does).
///
/// Instancing saves memory but costs traversal speed: on `irsig bench
/// trace`'s default scene (a 1 M-triangle terrain and 1000 instanced
/// 12-triangle buildings), the flat scene traced 2–3× more primary and
/// shadow rays per second than the instanced one
/// (`scripts/embree-harness/run`, docs/embree.md).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Instancing {
    /// Flatten a mesh when all its placements together have at most
    /// [`FLATTEN_TRIANGLES`] triangles; instance larger ones. The default.
    #[default]
    FlattenSmall,
    /// Every mesh placed more than once is an Embree instance.
    Always,
}

/// Flattening budget of [`Instancing::FlattenSmall`]: a mesh whose
/// placements total at most this many triangles is flattened (≈ 48 bytes
/// of vertices and indices per triangle plus Embree's BVH, ≈ 0.2 GB at the
/// budget).
pub const FLATTEN_TRIANGLES: usize = 2_000_000;

/// Embree tracer over a [`SceneGeometry`].
pub struct EmbreeTracer {
    /// The top-level scene; it keeps alive every vertex buffer and instanced
    /// scene it reads.
    scene: Scene<'static>,
    /// Per instance: the cofactor matrix turning an object-space geometric
    /// normal into world space, for instances traced through Embree
    /// instancing (Embree reports their `Ng` in object space).
    normal_from_object: Vec<Option<Mat3A>>,
    device: Device,
    mode: RayMode,
    name: &'static str,
}

/// Cofactor matrix of `m` (`det(m)·m⁻ᵀ`): maps `a×b` to `(m a)×(m b)`, so it
/// turns an object-space `(p1-p0)×(p2-p0)` into the world-space one.
fn cofactor(m: Mat3A) -> Mat3A {
    Mat3A::from_cols(
        m.y_axis.cross(m.z_axis),
        m.z_axis.cross(m.x_axis),
        m.x_axis.cross(m.y_axis),
    )
}

impl EmbreeTracer {
    /// Builds a watertight scene; `packets` selects
    /// [`RayMode::ByCoherence`] at the native width
    /// ([`Device::native_packet_width`]: packets for coherent batches,
    /// single rays for the rest) rather than single rays throughout.
    pub fn new(geom: &SceneGeometry, packets: bool) -> Result<Self> {
        Self::with_options(geom, packets, Watertight::Yes)
    }

    /// [`EmbreeTracer::new`] with the triangle tests chosen by `watertight`.
    pub fn with_options(
        geom: &SceneGeometry,
        packets: bool,
        watertight: Watertight,
    ) -> Result<Self> {
        let device = Device::new()?;
        let mode = if packets {
            RayMode::ByCoherence(device.native_packet_width())
        } else {
            RayMode::Single
        };
        Self::with_device(device, geom, mode, watertight)
    }

    /// Builds a watertight scene with an explicit ray mode; a packet width
    /// the library does not support natively is an error.
    pub fn with_mode(geom: &SceneGeometry, mode: RayMode) -> Result<Self> {
        Self::with_device(Device::new()?, geom, mode, Watertight::Yes)
    }

    /// Builds a scene on `device` (e.g. one made with
    /// [`Device::with_threads`]) with an explicit ray mode and triangle
    /// tests; a packet width the library does not support natively is an
    /// error.
    pub fn with_device(
        device: Device,
        geom: &SceneGeometry,
        mode: RayMode,
        watertight: Watertight,
    ) -> Result<Self> {
        Self::with_instancing(device, geom, mode, watertight, Instancing::FlattenSmall)
    }

    /// [`EmbreeTracer::with_device`] with the choice of which meshes placed
    /// more than once become Embree instances ([`Instancing`]).
    pub fn with_instancing(
        device: Device,
        geom: &SceneGeometry,
        mode: RayMode,
        watertight: Watertight,
        instancing: Instancing,
    ) -> Result<Self> {
        if mode == RayMode::Stream && !STREAM_API {
            return Err(Error::invalid(
                "ray mode",
                format!(
                    "Embree {} has no stream API (rtcIntersect1M); use single rays or packets",
                    device.version()
                ),
            ));
        }
        if let RayMode::Packet(w) | RayMode::ByCoherence(w) = mode {
            if !device.supports_packet_width(w) {
                return Err(Error::invalid(
                    "packet width",
                    format!(
                        "{w} is not supported by this Embree build/CPU (expected 4, 8 or 16; native is {})",
                        device.native_packet_width()
                    ),
                ));
            }
        }
        let mut uses = vec![0usize; geom.meshes.len()];
        for (i, inst) in geom.instances.iter().enumerate() {
            if inst.mesh >= geom.meshes.len() {
                return Err(Error::invalid(
                    format!("instances[{i}].mesh"),
                    format!(
                        "mesh index {} out of range ({} meshes)",
                        inst.mesh,
                        geom.meshes.len()
                    ),
                ));
            }
            uses[inst.mesh] += 1;
        }
        let mut top = Scene::new(&device, watertight)?;
        let mut mesh_scenes: Vec<Option<Arc<Scene<'static>>>> =
            (0..geom.meshes.len()).map(|_| None).collect();
        let mut normal_from_object = Vec::with_capacity(geom.instances.len());
        for (i, inst) in geom.instances.iter().enumerate() {
            let mesh = &geom.meshes[inst.mesh];
            let id = u32::try_from(i)
                .map_err(|_| Error::invalid("instances", "more than 2^32 instances"))?;
            let flatten = match instancing {
                Instancing::FlattenSmall => {
                    uses[inst.mesh].saturating_mul(mesh.indices.len()) <= FLATTEN_TRIANGLES
                }
                Instancing::Always => false,
            };
            if uses[inst.mesh] == 1 || flatten {
                // Placed once, or a small mesh: attach directly, in world
                // space.
                let vb = if inst.world_from_object == Affine3A::IDENTITY {
                    VertexBuffer::new(mesh.positions.iter().copied())
                } else {
                    VertexBuffer::new(
                        mesh.positions
                            .iter()
                            .map(|p| inst.world_from_object.transform_point3(*p)),
                    )
                };
                let g = Geometry::triangles_shared(&device, Arc::new(vb), &mesh.indices)?;
                top.attach(&g, id)?;
                normal_from_object.push(None);
            } else {
                if mesh_scenes[inst.mesh].is_none() {
                    let vb = VertexBuffer::new(mesh.positions.iter().copied());
                    let g = Geometry::triangles_shared(&device, Arc::new(vb), &mesh.indices)?;
                    let mut s = Scene::new(&device, watertight)?;
                    s.attach(&g, 0)?;
                    s.commit()?;
                    mesh_scenes[inst.mesh] = Some(Arc::new(s));
                }
                let s = mesh_scenes[inst.mesh].as_ref().expect("built above");
                let g = Geometry::instance(&device, s, &inst.world_from_object)?;
                top.attach(&g, id)?;
                normal_from_object.push(Some(cofactor(inst.world_from_object.matrix3)));
            }
        }
        top.commit()?;
        let name = match mode {
            RayMode::Single => "embree_single",
            RayMode::Packet(_) => "embree_packet",
            RayMode::Stream => "embree_stream",
            RayMode::ByCoherence(_) => "embree",
        };
        Ok(EmbreeTracer {
            scene: top,
            normal_from_object,
            device,
            mode,
            name,
        })
    }

    /// How rays are fed to Embree.
    pub fn mode(&self) -> RayMode {
        self.mode
    }

    /// The device.
    pub fn device(&self) -> &Device {
        &self.device
    }

    /// The hit of one single-ray query (`rtcIntersect1` or the stream).
    #[inline]
    fn single_hit(&self, rh: &raw::RTCRayHit) -> Option<Hit> {
        let h = &rh.hit;
        self.make_hit(
            rh.ray.tfar,
            h.geomID,
            h.instID[0],
            h.primID,
            h.u,
            h.v,
            Vec3::new(h.Ng_x, h.Ng_y, h.Ng_z),
        )
    }

    #[inline]
    #[allow(clippy::too_many_arguments)]
    fn make_hit(
        &self,
        t: f32,
        geom_id: u32,
        inst_id: u32,
        prim: u32,
        u: f32,
        v: f32,
        ng: Vec3,
    ) -> Option<Hit> {
        if geom_id == raw::RTC_INVALID_GEOMETRY_ID {
            return None;
        }
        let instance = if inst_id != raw::RTC_INVALID_GEOMETRY_ID {
            inst_id
        } else {
            geom_id
        };
        let ng = match self
            .normal_from_object
            .get(instance as usize)
            .copied()
            .flatten()
        {
            Some(c) => c * ng,
            None => ng,
        };
        Some(Hit {
            t,
            instance,
            prim,
            u,
            v,
            ng,
        })
    }

    /// Occlusion context for a packet width (see [`Device::native_packet_width`]:
    /// no coherent flag on 16-wide occlusion).
    /// Query arguments for an occlusion packet of `width` (see
    /// [`Device::native_packet_width`]: no coherent flag on 16-wide
    /// occlusion).
    fn occlusion_args(width: usize, coherence: Coherence) -> QueryArgs {
        if width == 16 {
            QueryArgs::new(Coherence::Incoherent)
        } else {
            QueryArgs::new(coherence)
        }
    }

    fn intersect_single(&self, rays: &[Ray], coherence: Coherence, out: &mut [Option<Hit>]) {
        let mut args = QueryArgs::new(coherence);
        for (r, o) in rays.iter().zip(out.iter_mut()) {
            let mut rh = raw::RTCRayHit {
                ray: single_ray(r),
                hit: raw::RTCHit {
                    geomID: raw::RTC_INVALID_GEOMETRY_ID,
                    instID: [raw::RTC_INVALID_GEOMETRY_ID],
                    ..Default::default()
                },
            };
            // SAFETY: committed scene; `args` initialised; `rh` is a valid,
            // 16-byte-aligned RTCRayHit (its type's alignment).
            unsafe {
                intersect_call!(single raw::rtcIntersect1, self.scene.raw, &mut args, &mut rh)
            };
            *o = self.single_hit(&rh);
        }
    }

    fn occluded_single(&self, rays: &[Ray], coherence: Coherence, out: &mut [bool]) {
        let mut args = QueryArgs::new(coherence);
        for (r, o) in rays.iter().zip(out.iter_mut()) {
            let mut ray = single_ray(r);
            // SAFETY: committed scene; `args` initialised; `ray` is a valid,
            // 16-byte-aligned RTCRay.
            unsafe {
                occluded_call!(single raw::rtcOccluded1, self.scene.raw, &mut args, &mut ray)
            };
            *o = ray.tfar == f32::NEG_INFINITY;
        }
    }
}

/// Whether the linked Embree has the stream API (`rtcIntersect1M`:
/// Embree 3 only), i.e. whether [`RayMode::Stream`] can be used.
pub const STREAM_API: bool = cfg!(not(embree4));

#[cfg(embree4)]
impl EmbreeTracer {
    fn intersect_stream(&self, _: &[Ray], _: Coherence, _: &mut [Option<Hit>]) {
        unreachable!("RayMode::Stream is refused on Embree 4 when the tracer is built")
    }

    fn occluded_stream(&self, _: &[Ray], _: Coherence, _: &mut [bool]) {
        unreachable!("RayMode::Stream is refused on Embree 4 when the tracer is built")
    }
}

#[cfg(not(embree4))]
impl EmbreeTracer {
    fn intersect_stream(&self, rays: &[Ray], coherence: Coherence, out: &mut [Option<Hit>]) {
        let mut args = QueryArgs::new(coherence);
        let mut rh: Vec<raw::RTCRayHit> = rays
            .iter()
            .map(|r| raw::RTCRayHit {
                ray: single_ray(r),
                hit: raw::RTCHit {
                    geomID: raw::RTC_INVALID_GEOMETRY_ID,
                    instID: [raw::RTC_INVALID_GEOMETRY_ID],
                    ..Default::default()
                },
            })
            .collect();
        for c in rh.chunks_mut(u32::MAX as usize) {
            // SAFETY: committed scene; `args` initialised; `c` holds `c.len()`
            // valid, 16-byte-aligned RTCRayHit at a stride of their size.
            unsafe {
                raw::rtcIntersect1M(
                    self.scene.raw,
                    &mut args.0,
                    c.as_mut_ptr(),
                    c.len() as u32,
                    std::mem::size_of::<raw::RTCRayHit>(),
                )
            };
        }
        for (rh, o) in rh.iter().zip(out.iter_mut()) {
            *o = self.single_hit(rh);
        }
    }

    /// Never with the coherent flag: Embree 3.13.5's coherent stream
    /// occlusion forms native-width packets, and on AVX-512 machines (16
    /// wide) it was seen to loop forever on scattered rays, as
    /// `rtcOccluded16` does (see [`Device::native_packet_width`]).
    fn occluded_stream(&self, rays: &[Ray], _coherence: Coherence, out: &mut [bool]) {
        let mut args = QueryArgs::new(Coherence::Incoherent);
        let mut rs: Vec<raw::RTCRay> = rays.iter().map(single_ray).collect();
        for c in rs.chunks_mut(u32::MAX as usize) {
            // SAFETY: committed scene; `args` initialised; `c` holds `c.len()`
            // valid, 16-byte-aligned RTCRay at a stride of their size.
            unsafe {
                raw::rtcOccluded1M(
                    self.scene.raw,
                    &mut args.0,
                    c.as_mut_ptr(),
                    c.len() as u32,
                    std::mem::size_of::<raw::RTCRay>(),
                )
            };
        }
        for (r, o) in rs.iter().zip(out.iter_mut()) {
            *o = r.tfar == f32::NEG_INFINITY;
        }
    }
}

fn single_ray(r: &Ray) -> raw::RTCRay {
    raw::RTCRay {
        org_x: r.origin.x,
        org_y: r.origin.y,
        org_z: r.origin.z,
        tnear: r.tnear,
        dir_x: r.dir.x,
        dir_y: r.dir.y,
        dir_z: r.dir.z,
        time: 0.0,
        tfar: r.tfar,
        mask: u32::MAX,
        id: 0,
        flags: 0,
    }
}

/// Writes ray `r` into lane `i` of an `RTCRayN` packet (SoA): every field,
/// with the mask all-ones (masks are compiled into Debian's Embree).
macro_rules! fill_lane {
    ($ray:expr, $i:expr, $r:expr) => {{
        let (ray, i, r) = (&mut $ray, $i, $r);
        ray.org_x[i] = r.origin.x;
        ray.org_y[i] = r.origin.y;
        ray.org_z[i] = r.origin.z;
        ray.tnear[i] = r.tnear;
        ray.dir_x[i] = r.dir.x;
        ray.dir_y[i] = r.dir.y;
        ray.dir_z[i] = r.dir.z;
        ray.time[i] = 0.0;
        ray.tfar[i] = r.tfar;
        ray.mask[i] = u32::MAX;
        ray.id[i] = i as u32;
        ray.flags[i] = 0;
    }};
}

/// Generates the packet paths for one width.
macro_rules! packet_paths {
    ($w:literal, $isect_name:ident, $occl_name:ident, $rayhit:ty, $ray:ty, $isect:path, $occl:path) => {
        impl EmbreeTracer {
            fn $isect_name(&self, rays: &[Ray], coherence: Coherence, out: &mut [Option<Hit>]) {
                let mut args = QueryArgs::new(coherence);
                let mut valid = Valid::<$w>([0; $w]);
                let mut rh = <$rayhit>::default();
                for (rc, oc) in rays.chunks($w).zip(out.chunks_mut($w)) {
                    for i in 0..$w {
                        // Padding lanes repeat the first ray, marked invalid.
                        let r = rc.get(i).unwrap_or(&rc[0]);
                        valid.0[i] = if i < rc.len() { -1 } else { 0 };
                        fill_lane!(rh.ray, i, r);
                        rh.hit.geomID[i] = raw::RTC_INVALID_GEOMETRY_ID;
                        rh.hit.instID[0][i] = raw::RTC_INVALID_GEOMETRY_ID;
                    }
                    // SAFETY: committed scene; `args` initialised; `valid` and
                    // `rh` have the alignment Embree requires for this width
                    // (`Valid` is 64-byte aligned, the RTCRayHitN type carries
                    // its own alignment) and every lane is initialised.
                    unsafe { intersect_call!(packet $isect, valid.0.as_ptr(), self.scene.raw, &mut args, &mut rh) };
                    let h = &rh.hit;
                    for (i, o) in oc.iter_mut().enumerate() {
                        *o = self.make_hit(
                            rh.ray.tfar[i],
                            h.geomID[i],
                            h.instID[0][i],
                            h.primID[i],
                            h.u[i],
                            h.v[i],
                            Vec3::new(h.Ng_x[i], h.Ng_y[i], h.Ng_z[i]),
                        );
                    }
                }
            }

            fn $occl_name(&self, rays: &[Ray], coherence: Coherence, out: &mut [bool]) {
                let mut args = Self::occlusion_args($w, coherence);
                let mut valid = Valid::<$w>([0; $w]);
                let mut ray = <$ray>::default();
                for (rc, oc) in rays.chunks($w).zip(out.chunks_mut($w)) {
                    for i in 0..$w {
                        let r = rc.get(i).unwrap_or(&rc[0]);
                        valid.0[i] = if i < rc.len() { -1 } else { 0 };
                        fill_lane!(ray, i, r);
                    }
                    // SAFETY: as for the intersect path: committed scene,
                    // initialised context, aligned valid mask and ray packet.
                    unsafe { occluded_call!(packet $occl, valid.0.as_ptr(), self.scene.raw, &mut args, &mut ray) };
                    for (i, o) in oc.iter_mut().enumerate() {
                        *o = ray.tfar[i] == f32::NEG_INFINITY;
                    }
                }
            }
        }
    };
}

packet_paths!(
    4,
    intersect4,
    occluded4,
    raw::RTCRayHit4,
    raw::RTCRay4,
    raw::rtcIntersect4,
    raw::rtcOccluded4
);
packet_paths!(
    8,
    intersect8,
    occluded8,
    raw::RTCRayHit8,
    raw::RTCRay8,
    raw::rtcIntersect8,
    raw::rtcOccluded8
);
packet_paths!(
    16,
    intersect16,
    occluded16,
    raw::RTCRayHit16,
    raw::RTCRay16,
    raw::rtcIntersect16,
    raw::rtcOccluded16
);

impl Tracer for EmbreeTracer {
    fn name(&self) -> &str {
        self.name
    }

    fn intersect(&self, rays: &[Ray], coherence: Coherence, out: &mut [Option<Hit>]) {
        assert_eq!(
            rays.len(),
            out.len(),
            "intersect: rays and out differ in length"
        );
        let _ftz = FlushDenormals::new();
        match self.mode.for_batch(coherence) {
            RayMode::Single => self.intersect_single(rays, coherence, out),
            RayMode::Stream => self.intersect_stream(rays, coherence, out),
            RayMode::Packet(4) => self.intersect4(rays, coherence, out),
            RayMode::Packet(8) => self.intersect8(rays, coherence, out),
            RayMode::Packet(_) | RayMode::ByCoherence(_) => self.intersect16(rays, coherence, out),
        }
    }

    fn occluded(&self, rays: &[Ray], coherence: Coherence, out: &mut [bool]) {
        assert_eq!(
            rays.len(),
            out.len(),
            "occluded: rays and out differ in length"
        );
        let _ftz = FlushDenormals::new();
        match self.mode.for_batch(coherence) {
            RayMode::Single => self.occluded_single(rays, coherence, out),
            RayMode::Stream => self.occluded_stream(rays, coherence, out),
            RayMode::Packet(4) => self.occluded4(rays, coherence, out),
            RayMode::Packet(8) => self.occluded8(rays, coherence, out),
            RayMode::Packet(_) | RayMode::ByCoherence(_) => self.occluded16(rays, coherence, out),
        }
    }
}

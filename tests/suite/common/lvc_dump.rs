//! An [`Observer`] that reads back what every stage of the light-vertex-cache
//! integrators leaves in the GPU's buffers, for the tests that compare the kernels with
//! their CPU twins and their MIS weights with the oracle.

use splitray::integrator::lvc::camera_pass::BounceView;
use splitray::integrator::lvc::gpu::{Contribution, LvcVertex};
use splitray::integrator::lvc::light_tracing::SplatBatch;
use splitray::integrator::lvc::{ChunkView, LvcIntegrator, LvcOptions, Observer, Shared};
use splitray::integrator::pt::PtScene;
use splitray::scene::Scene;
use splitray::trace::{Hit, Ray, TracerKind};
use splitray::vk::{self, Buffer, Gpu};

/// What one camera bounce left.
pub struct BounceDump {
    pub view_paths: u32,
    pub base: u32,
    pub pixel_offset: u32,
    pub pixel_count: u32,
    pub bounce: u32,
    pub active: Vec<u32>,
    /// The bounce's closest hits and, when sorting is on, the live paths' positions in
    /// material order (the shading kernels' `order`).
    pub closest: Vec<Hit>,
    pub order: Vec<u32>,
    pub vertices: Vec<LvcVertex>,
    pub emitted: Vec<Contribution>,
    pub contributions: Vec<Contribution>,
    pub rays: Vec<Ray>,
    pub hits: Vec<Hit>,
    pub radiance: Vec<[f32; 4]>,
}

/// What one chunk left.
pub struct ChunkDump {
    pub chunk: ChunkView,
    pub cache: Vec<LvcVertex>,
    pub index: Vec<u32>,
    pub path_offset: Vec<u32>,
    pub splats: Vec<Contribution>,
    pub splat_rays: Vec<Ray>,
    pub splat_hits: Vec<Hit>,
    pub splat_film: Vec<u32>,
    pub bounces: Vec<BounceDump>,
}

#[derive(Default)]
pub struct Dumps {
    pub chunks: Vec<ChunkDump>,
}

fn read<T: bytemuck::Pod>(b: &Buffer, n: usize) -> vk::Result<Vec<T>> {
    let mut v: Vec<T> = b.read()?;
    v.truncate(n);
    Ok(v)
}

impl Observer for Dumps {
    fn light_pass(&mut self, s: &Shared, chunk: &ChunkView) -> vk::Result<()> {
        let n = chunk.vertices as usize;
        self.chunks.push(ChunkDump {
            chunk: *chunk,
            cache: read(&s.cache.vertices, n)?,
            index: read(&s.cache.index, n)?,
            path_offset: read(&s.cache.path_offset, chunk.light_paths as usize + 1)?,
            splats: Vec::new(),
            splat_rays: Vec::new(),
            splat_hits: Vec::new(),
            splat_film: Vec::new(),
            bounces: Vec::new(),
        });
        Ok(())
    }

    fn splats(&mut self, s: &Shared, _chunk: &ChunkView, batch: &SplatBatch) -> vk::Result<()> {
        let n = batch.count as usize;
        let c = self.chunks.last_mut().unwrap();
        c.splats
            .extend(read::<Contribution>(&s.wave.contributions, n)?);
        c.splat_rays.extend(read::<Ray>(&s.wave.shadow_rays, n)?);
        c.splat_hits.extend(read::<Hit>(&s.wave.shadow_hits, n)?);
        Ok(())
    }

    fn splat_film(&mut self, film: &Buffer, _chunk: &ChunkView) -> vk::Result<()> {
        self.chunks.last_mut().unwrap().splat_film = film.read()?;
        Ok(())
    }

    fn bounce(&mut self, s: &Shared, _chunk: &ChunkView, v: &BounceView) -> vk::Result<()> {
        let w = s.wave;
        let n = v.paths as usize;
        let slots = v.connection_base as usize + n * s.connections as usize;
        let paths = (v.range.passes * v.range.pixel_count) as usize;
        self.chunks.last_mut().unwrap().bounces.push(BounceDump {
            view_paths: v.paths,
            base: v.connection_base,
            pixel_offset: v.range.pixel_offset,
            pixel_count: v.range.pixel_count,
            bounce: v.bounce,
            active: read(&w.active[v.list], n)?,
            closest: read(&w.hits, n)?,
            order: read(&w.order, n)?,
            vertices: read(&w.vertices, n)?,
            emitted: read(&w.emitted, n)?,
            contributions: read(&w.contributions, slots)?,
            rays: read(&w.shadow_rays, slots)?,
            hits: read(&w.shadow_hits, slots)?,
            radiance: read(&w.radiance, paths)?,
        });
        Ok(())
    }
}

/// Renders `passes` passes of `scene` on a `width` × `height` film, observing every chunk.
pub fn render(
    gpu: &Gpu,
    scene: &Scene,
    width: u32,
    height: u32,
    options: &LvcOptions,
    passes: u32,
) -> (Dumps, LvcIntegrator<'static>) {
    let pt = PtScene::new(scene);
    let tracer = TracerKind::default().create(gpu, &pt.triangles).unwrap();
    let frame = scene.camera.frame(width, height);
    let mut lvc = LvcIntegrator::new(gpu, tracer, &pt, &frame, options).unwrap();
    let mut dumps = Dumps::default();
    lvc.render_observed(0, passes, &mut dumps).unwrap();
    (dumps, lvc)
}

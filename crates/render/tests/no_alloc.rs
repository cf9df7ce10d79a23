//! Rendering allocates nothing once warmed up: a counting global allocator checks it.
// NOTE: a global allocator must implement the unsafe `GlobalAlloc` trait; it only forwards to
// the system allocator and counts.
#![allow(unsafe_code)]

use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::atomic::{AtomicUsize, Ordering};

use cloth_mesh::{ClothMesh, ClothState, GridSpec, Vec3};
use cloth_mesh::{Collider, Plane, Sphere};
use cloth_render::{AsciiFrame, Mode, RenderOptions, Renderer, View, ViewSpec};

struct Counting;

static ALLOCATIONS: AtomicUsize = AtomicUsize::new(0);

unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        ALLOCATIONS.fetch_add(1, Ordering::SeqCst);
        unsafe { System.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        unsafe { System.dealloc(ptr, layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        ALLOCATIONS.fetch_add(1, Ordering::SeqCst);
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

#[test]
fn a_warm_renderer_draws_every_mode_and_view_without_allocating() {
    let mesh = ClothMesh::new(&GridSpec {
        pinned: vec![(0, 0), (49, 0)],
        ..GridSpec::default()
    })
    .unwrap();
    let mut state = ClothState::new(&mesh);
    let colliders = [
        Collider::Sphere(Sphere {
            origin: Vec3::new(0.5, 0.2, 0.5),
            radius: 0.2,
            friction: 0.3,
        }),
        Collider::Plane(Plane {
            point: Vec3::zeros(),
            normal: Vec3::y(),
            friction: 0.5,
        }),
    ];
    let mut renderer = Renderer::new();
    let mut frame = AsciiFrame::with_size(200, 60).unwrap();
    let mut text = String::with_capacity(1 << 20);
    let jobs: Vec<(ViewSpec, RenderOptions)> = Mode::ALL
        .into_iter()
        .flat_map(|mode| View::ALL.into_iter().map(move |view| (view, mode)))
        .map(|(view, mode)| {
            (
                ViewSpec::new(view, &mesh),
                RenderOptions {
                    mode,
                    legend: true,
                    ..RenderOptions::default()
                },
            )
        })
        .collect();
    // Warm up at the largest pixel grid (braille), then every job must reuse the buffers.
    for (view, options) in &jobs {
        renderer
            .render(&mesh, &state, &colliders, view, options, &mut frame)
            .unwrap();
    }
    for p in &mut state.positions {
        p.y -= 0.3;
    }
    let before = ALLOCATIONS.load(Ordering::SeqCst);
    for (view, options) in &jobs {
        renderer
            .render(&mesh, &state, &colliders, view, options, &mut frame)
            .unwrap();
        text.clear();
        frame
            .write_ansi(&mut text, cloth_render::ColorDepth::TrueColor)
            .unwrap();
    }
    assert_eq!(ALLOCATIONS.load(Ordering::SeqCst) - before, 0);
}

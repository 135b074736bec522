//! Generator of the bundled default scene, `scenes/town/scene.json`
//! (`irsig scene town --out scenes/town/scene.json`).
//!
//! A small industrial town modelled loosely on the area of Kodak's Hawkeye
//! plant in Rochester, NY (43.16° N, 77.61° W, about 160 m above sea level):
//! a 600 m × 600 m terrain grid whose cells are classified as streets,
//! parking lots, sidewalks, lawns, bare soil and a pond bank; a large
//! flat-roofed plant building with a smokestack, rooftop units and storage
//! tanks; a brick church with a spire; rows of houses with shingle roofs;
//! instanced deciduous and coniferous trees; a pond; parked cars (some with
//! running engines: `self_power_w_m2` on the engine part) and an armoured
//! vehicle. Everything is built from primitives and instancing, so the file
//! stays small; the output is deterministic.
//!
//! Built surfaces are layered constructions of `scenes/materials.json`:
//! streets and parking lots `asphalt_road` (asphalt on a crushed-stone base
//! on the soil), the plant's roof `flat_roof_insulated`, its walls
//! `insulated_metal_panel`, brick walls `brick_cavity_wall`, clapboard walls
//! `wood_frame_wall`. Walls and flat roofs have the building interior
//! behind them ([`interior`]: suited to the season of [`TOWN_TIME`]);
//! pitched roofs and gables keep their ventilated attic (their materials'
//! `exposed_area`).
//!
//! Owns the town's layout and its random placements. Takes nothing; gives
//! the scene JSON ([`town_scene`]), the same document a user would write.
//! Must not know how scenes are loaded or rendered.

use rand::{Rng, SeedableRng};
use rand_xoshiro::SplitMix64;
use serde_json::{Value, json};

use super::file::{Bowl, Flat, HeightFunction, Wave};
use super::height_function;

/// The scene's image time (local, RFC 3339).
pub const TOWN_TIME: &str = "2025-06-21T14:00:00-04:00";

/// Whether a month (1–12) lies in the cooling season of the northern
/// mid-latitudes (May–September; the town is at 43° N).
fn cooling_season(month: u32) -> bool {
    (5..=9).contains(&month)
}

/// The interior behind the town's walls (`roof: false`) and flat roofs in
/// the season of `month`, as a scene-file `back`:
/// - heating season: held at 20 °C, the EN 16798-1:2019 category II design
///   value for heating;
/// - cooling season: set points 20 °C (heating) and 26 °C (cooling,
///   EN 16798-1 category II), free-floating at the outdoor air between —
///   cooled on a hot afternoon, at 20 °C on a cool night.
///
/// Film coefficients `1/R_si` from EN ISO 6946:2017 Table 7: walls
/// `1/0.13`; roofs `1/0.10` when heat flows up (a heated room under a cold
/// roof) and `1/0.17` when it flows down (a sun-heated roof over a cooled
/// room).
pub fn interior(month: u32, roof: bool) -> Value {
    let r_si: f64 = match (roof, cooling_season(month)) {
        (false, _) => 0.13,
        (true, false) => 0.10,
        (true, true) => 0.17,
    };
    let h = (1.0 / r_si * 100.0).round() / 100.0;
    if cooling_season(month) {
        json!({"interior": {"heating_setpoint_k": 293.15, "cooling_setpoint_k": 299.15,
                            "film_coefficient_w_m2_k": h}})
    } else {
        json!({"interior": {"air_temperature_k": 293.15, "film_coefficient_w_m2_k": h}})
    }
}

/// Half-extent of the terrain, m.
const HALF: f64 = 300.0;
/// Terrain cells each way.
const CELLS: usize = 300;

/// Axis-aligned rectangle `[x0, y0, x1, y1]`.
type Rect = [f64; 4];

fn inside(r: &Rect, x: f64, y: f64) -> bool {
    x >= r[0] && x <= r[2] && y >= r[1] && y <= r[3]
}

struct Layout {
    terrain: HeightFunction,
    /// Rectangles classified, later entries win: (class char, rect).
    zones: Vec<(char, Rect)>,
    pond: ([f64; 2], f64),
}

fn layout() -> Layout {
    let plant_pad = Flat {
        min: [-95.0, 10.0],
        max: [95.0, 115.0],
        height_m: 1.0,
        blend_m: 25.0,
    };
    let church_pad = Flat {
        min: [160.0, -150.0],
        max: [215.0, -95.0],
        height_m: 0.6,
        blend_m: 15.0,
    };
    let pond = ([150.0, 175.0], 38.0);
    let terrain = HeightFunction {
        base_m: 0.0,
        slope: Some([0.0, 0.004]),
        waves: vec![
            Wave {
                amplitude_m: 1.2,
                wavelength_m: 420.0,
                direction_deg: 30.0,
                phase_rad: 0.4,
            },
            Wave {
                amplitude_m: 0.5,
                wavelength_m: 170.0,
                direction_deg: 110.0,
                phase_rad: 1.3,
            },
        ],
        bowls: vec![Bowl {
            center: pond.0,
            radius_m: pond.1 + 8.0,
            depth_m: 2.5,
        }],
        flats: vec![plant_pad, church_pad],
    };
    let mut zones: Vec<(char, Rect)> = vec![
        // Everything starts as lawn ('g'); residential yards and park.
        ('s', [120.0, 40.0, 295.0, 110.0]), // bare lot east of the plant
        ('d', [230.0, 60.0, 270.0, 95.0]),  // sand pile on the lot
        ('c', [-100.0, 5.0, 100.0, 120.0]), // plant apron
        ('a', [-95.0, -25.0, 95.0, 2.0]),   // main parking lot
        ('a', [-300.0, -45.0, 300.0, -33.0]), // Main Street (E-W)
        ('c', [-300.0, -49.0, 300.0, -45.0]), // sidewalk S
        ('c', [-300.0, -33.0, 300.0, -29.0]), // sidewalk N
        ('a', [105.0, -300.0, 115.0, 300.0]), // Mill Road (N-S)
        ('a', [-300.0, 128.0, 105.0, 136.0]), // north service road
        ('a', [-205.0, -300.0, -197.0, 300.0]), // residential street
        ('a', [-300.0, -160.0, -105.0, -153.0]), // residential cross street
        ('c', [165.0, -145.0, 210.0, -100.0]), // church plaza (under church)
        ('a', [140.0, -95.0, 230.0, -75.0]), // church parking
    ];
    // Driveways of the houses.
    for (x, y, _) in house_sites() {
        let dx = if x < -201.0 { 1.0 } else { -1.0 };
        let (x0, x1) = if dx > 0.0 {
            (x + 5.0, -205.0)
        } else {
            (-197.0, x - 5.0)
        };
        zones.push(('c', [x0.min(x1), y - 1.5, x0.max(x1), y + 1.5]));
    }
    Layout {
        terrain,
        zones,
        pond,
    }
}

/// Houses west and east of the residential street: (x, y, rotation deg).
fn house_sites() -> Vec<(f64, f64, f64)> {
    let mut v = Vec::new();
    for k in 0..9 {
        let y = -270.0 + 46.0 * k as f64;
        if (y + 156.0).abs() < 20.0 || (y + 39.0).abs() < 22.0 || (y - 132.0).abs() < 20.0 {
            continue;
        }
        v.push((-230.0, y, 90.0));
        v.push((-172.0, y + 12.0, -90.0));
        v.push((-272.0, y + 20.0, 90.0));
        v.push((-135.0, y - 6.0, -90.0));
    }
    v
}

fn class_at(l: &Layout, x: f64, y: f64) -> char {
    let d = ((x - l.pond.0[0]).powi(2) + (y - l.pond.0[1]).powi(2)).sqrt();
    if d < l.pond.1 + 6.0 {
        return 's'; // pond bottom and muddy bank
    }
    let mut c = 'g';
    for (k, r) in &l.zones {
        if inside(r, x, y) {
            c = *k;
        }
    }
    c
}

fn tf(x: f64, y: f64, z: f64, rot_z: f64) -> Value {
    let r = |v: f64| (v * 1000.0).round() / 1000.0;
    if rot_z == 0.0 {
        json!({"translate": [r(x), r(y), r(z)]})
    } else {
        json!({"translate": [r(x), r(y), r(z)], "rotate_deg": [0.0, 0.0, r(rot_z)]})
    }
}

/// The generator of the town's random placements (tree sizes and turns,
/// empty parking spaces, park positions).
///
/// Not ChaCha8 like irsig's other seeded draws: the committed
/// `scenes/town/scene.json`, and with it the default render, are fixed by
/// this generator's sequence — SplitMix64 (Steele, Lea & Flood 2014) from
/// state `0x1A5E_5EED`, each draw `(next_u64 >> 11) · 2⁻⁵³` in [0, 1)
/// (`rand`'s standard `f64`), taken from `rand_xoshiro`. Changing it
/// changes the bundled scene.
fn town_rng() -> SplitMix64 {
    SplitMix64::seed_from_u64(0x1A5E_5EED)
}

fn car_shapes() -> Value {
    let mut shapes = vec![
        json!({"box": {"size": [3.2, 1.8, 0.75], "bottom": false}, "part": "body",
               "transform": {"translate": [-0.6, 0.0, 0.35]}}),
        json!({"box": {"size": [1.3, 1.8, 0.7], "bottom": false}, "part": "engine",
               "transform": {"translate": [1.65, 0.0, 0.35]}}),
        json!({"box": {"size": [2.2, 1.6, 0.55], "bottom": false}, "part": "cabin",
               "transform": {"translate": [-0.5, 0.0, 1.1]}}),
    ];
    for (x, y) in [(1.4, 0.8), (1.4, -0.8), (-1.4, 0.8), (-1.4, -0.8)] {
        shapes.push(json!({"cylinder": {"radius": 0.33, "height": 0.22, "segments": 10},
            "part": "tyres",
            "transform": {"rotate_deg": [90.0, 0.0, 0.0], "translate": [x, if y > 0.0 { y + 0.22 } else { y }, 0.33]}}));
    }
    Value::Array(shapes)
}

fn car_parts(running: bool) -> Value {
    let mut engine = json!({"name": "engine", "material": "painted_steel"});
    if running {
        // A running (idling) engine heats the hood: a few hundred W/m².
        engine["self_power_w_m2"] = json!(400.0);
    }
    json!([
        {"name": "body", "material": "painted_steel"},
        engine,
        {"name": "cabin", "material": "glass"},
        {"name": "tyres", "material": "rubber_tire"}
    ])
}

/// The bundled town scene as JSON (what `scenes/town/scene.json` holds).
pub fn town_scene() -> Value {
    let l = layout();
    let month = chrono::DateTime::parse_from_rfc3339(TOWN_TIME)
        .map(|t| chrono::Datelike::month(&t))
        .expect("a valid RFC 3339 time");
    let wall_in = interior(month, false);
    let roof_in = interior(month, true);
    let h = |x: f64, y: f64| height_function(&l.terrain, x, y);
    let cell = 2.0 * HALF / CELLS as f64;
    // Class map, first row = north.
    let rows: Vec<String> = (0..CELLS)
        .map(|r| {
            let j = CELLS - 1 - r;
            (0..CELLS)
                .map(|i| {
                    let x = -HALF + (i as f64 + 0.5) * cell;
                    let y = -HALF + (j as f64 + 0.5) * cell;
                    class_at(&l, x, y)
                })
                .collect()
        })
        .collect();
    let mut objects = Vec::new();
    objects.push(json!({
        "name": "terrain",
        "description": "600 m x 600 m ground, 2 m cells, classified from the town layout",
        "shapes": [{"heightmap": {
            "size": [2.0 * HALF, 2.0 * HALF],
            "cells": [CELLS, CELLS],
            "function": serde_json::to_value(&l.terrain).expect("serialises"),
            "classes": {"legend": {"g": "grass", "a": "asphalt_road", "c": "concrete",
                                    "s": "bare_soil", "d": "sand"},
                        "rows": rows}
        }}]
    }));
    // The plant: a large flat-roofed building with a sawtooth of rooftop units.
    let pz = h(0.0, 60.0);
    objects.push(json!({
        "name": "plant_building",
        "description": "Main plant building, 160 m x 80 m x 14 m, insulated flat roof, metal-panel walls",
        "shapes": [
            {"box": {"size": [160.0, 80.0, 14.0], "max_edge_m": 4.0, "bottom": false}},
            {"box": {"size": [40.0, 30.0, 6.0], "max_edge_m": 4.0, "bottom": false},
             "transform": {"translate": [-60.0, -55.0, 0.0]}, "part": "annex"}
        ],
        "parts": [
            {"name": "top", "material": "flat_roof_insulated", "back": roof_in},
            {"name": "sides", "material": "insulated_metal_panel", "back": wall_in},
            {"name": "annex", "material": "brick_cavity_wall", "back": wall_in}
        ],
        "transform": tf(0.0, 60.0, pz - 0.3, 0.0)
    }));
    objects.push(json!({
        "name": "smokestack",
        "shapes": [{"cylinder": {"radius": 2.5, "height": 45.0, "segments": 24, "caps": false}}],
        "material": "brick",
        "parts": [{"name": "side", "material": "brick", "self_power_w_m2": 150.0}],
        "transform": tf(70.0, 90.0, h(70.0, 90.0) - 0.3, 0.0)
    }));
    let units: Vec<Value> = (0..8)
        .map(|k| {
            tf(
                -60.0 + 17.0 * k as f64,
                60.0 + if k % 2 == 0 { 15.0 } else { -15.0 },
                pz - 0.3 + 14.0,
                0.0,
            )
        })
        .collect();
    objects.push(json!({
        "name": "rooftop_unit",
        "description": "HVAC units on the plant roof; running compressors",
        "shapes": [{"box": {"size": [6.0, 4.0, 2.5], "bottom": false}}],
        "parts": [{"name": "top", "material": "painted_steel", "self_power_w_m2": 120.0},
                  {"name": "sides", "material": "painted_steel", "self_power_w_m2": 120.0}],
        "instances": units
    }));
    let tanks: Vec<Value> = [(-130.0, 95.0), (-130.0, 70.0), (-150.0, 82.0)]
        .iter()
        .map(|&(x, y)| tf(x, y, h(x, y) - 0.2, 0.0))
        .collect();
    objects.push(json!({
        "name": "storage_tank",
        "shapes": [{"cylinder": {"radius": 8.0, "height": 12.0, "segments": 32}}],
        "material": "painted_steel",
        "parts": [{"name": "side", "material": "painted_steel", "thickness_m": 0.008}],
        "instances": tanks
    }));
    // The church: nave, gable roof, tower, spire.
    let (cx, cy) = (188.0, -122.0);
    objects.push(json!({
        "name": "church",
        "shapes": [
            {"box": {"size": [14.0, 32.0, 10.0], "max_edge_m": 2.0, "bottom": false}, "part": "walls"},
            {"gable_roof": {"width": 14.0, "depth": 32.0, "height": 7.0, "overhang": 0.6},
             "transform": {"translate": [0.0, 0.0, 10.0]}},
            {"box": {"size": [7.0, 7.0, 24.0], "max_edge_m": 2.0, "bottom": false},
             "transform": {"translate": [0.0, 19.5, 0.0]}, "part": "walls"},
            {"cone": {"radius": 4.6, "height": 16.0, "segments": 8, "cap": false},
             "transform": {"translate": [0.0, 19.5, 24.0], "rotate_deg": [0.0, 0.0, 22.5]}, "part": "spire"}
        ],
        "parts": [
            {"name": "walls", "material": "brick", "thickness_m": 0.4, "back": wall_in},
            {"name": "roof", "material": "asphalt_shingle_roof"},
            {"name": "gables", "material": "brick", "thickness_m": 0.4},
            {"name": "spire", "material": "asphalt_shingle_roof", "exposed_area": 1.0}
        ],
        "transform": tf(cx, cy, h(cx, cy) - 0.3, 0.0)
    }));
    // Houses: two variants, instanced.
    let sites = house_sites();
    let (a, b): (Vec<_>, Vec<_>) = sites.iter().enumerate().partition(|(i, _)| i % 3 != 2);
    for (name, list, wall, size, roof_h) in [
        (
            "house_clapboard",
            a,
            ("wood_frame_wall", "wood_siding"),
            [9.0, 12.0, 5.5],
            3.5,
        ),
        (
            "house_brick",
            b,
            ("brick_cavity_wall", "brick"),
            [10.0, 13.0, 3.2],
            3.0,
        ),
    ] {
        let inst: Vec<Value> = list
            .iter()
            .map(|(_, (x, y, r))| tf(*x, *y, h(*x, *y) - 0.2, *r))
            .collect();
        objects.push(json!({
            "name": name,
            "shapes": [
                {"box": {"size": size, "max_edge_m": 3.0, "bottom": false}, "part": "walls"},
                {"gable_roof": {"width": size[0], "depth": size[1], "height": roof_h, "overhang": 0.4},
                 "transform": {"translate": [0.0, 0.0, size[2]]}}
            ],
            "parts": [
                {"name": "walls", "material": wall.0, "back": wall_in},
                {"name": "roof", "material": "asphalt_shingle_roof"},
                {"name": "gables", "material": wall.1}
            ],
            "instances": inst
        }));
    }
    // Trees: along streets, in yards and a park north-west.
    let mut rng = town_rng();
    let mut decid = Vec::new();
    let mut conif = Vec::new();
    let mut place = |x: f64, y: f64, rng: &mut SplitMix64, conifer: bool| {
        let s = 0.8 + 0.4 * rng.random::<f64>();
        let rot = (360.0 * rng.random::<f64>()).round();
        let mut t = tf(x, y, h(x, y) - 0.1, rot);
        t["scale"] = json!((s * 100.0_f64).round() / 100.0);
        if conifer {
            conif.push(t)
        } else {
            decid.push(t)
        }
    };
    for k in 0..24 {
        let x = -290.0 + 25.0 * k as f64;
        if (x - 110.0).abs() < 12.0 || (x + 201.0).abs() < 10.0 {
            continue;
        }
        place(x, -54.0, &mut rng, false);
        place(x + 12.0, -24.0, &mut rng, false);
    }
    for (x, y, _) in &sites {
        let side = if *x < -201.0 { -1.0 } else { 1.0 };
        let (dy, conifer) = (8.0 * rng.random::<f64>(), rng.random::<f64>() < 0.3);
        place(x + side * 12.0, y + dy, &mut rng, conifer);
    }
    for _ in 0..70 {
        // Park north-west of the plant (lawn), avoiding the service road.
        let x = -290.0 + 170.0 * rng.random::<f64>();
        let y = 150.0 + 140.0 * rng.random::<f64>();
        let conifer = rng.random::<f64>() < 0.5;
        place(x, y, &mut rng, conifer);
    }
    for k in 0..18 {
        // Ring of trees around the pond.
        let a = std::f64::consts::TAU * k as f64 / 18.0;
        let (x, y) = (l.pond.0[0] + 50.0 * a.cos(), l.pond.0[1] + 50.0 * a.sin());
        place(x, y, &mut rng, k % 3 == 0);
    }
    objects.push(json!({
        "name": "deciduous_tree",
        "shapes": [
            {"cylinder": {"radius": 0.25, "height": 4.0, "segments": 6, "caps": false}, "part": "trunk"},
            {"sphere": {"radius": 1.0, "segments": 16, "rings": 10}, "part": "crown",
             "transform": {"scale": [3.5, 3.5, 3.0], "translate": [0.0, 0.0, 6.0]}}
        ],
        "parts": [
            {"name": "trunk", "material": "tree_bark"},
            {"name": "crown", "material": "deciduous_canopy"}
        ],
        "instances": decid
    }));
    objects.push(json!({
        "name": "coniferous_tree",
        "shapes": [
            {"cylinder": {"radius": 0.2, "height": 2.0, "segments": 6, "caps": false}, "part": "trunk"},
            {"cone": {"radius": 2.6, "height": 6.0, "segments": 12}, "part": "crown",
             "transform": {"translate": [0.0, 0.0, 1.5]}},
            {"cone": {"radius": 1.8, "height": 5.0, "segments": 12}, "part": "crown",
             "transform": {"translate": [0.0, 0.0, 5.0]}}
        ],
        "parts": [
            {"name": "trunk", "material": "tree_bark"},
            {"name": "crown", "material": "coniferous_canopy"}
        ],
        "instances": conif
    }));
    // Pond surface: a plane at the water level; the terrain hides it outside
    // the bowl.
    let wl = h(l.pond.0[0] + l.pond.1, l.pond.0[1]) - 0.4;
    objects.push(json!({
        "name": "pond",
        "shapes": [{"plane": {"size": [2.0 * l.pond.1 + 12.0, 2.0 * l.pond.1 + 12.0], "max_edge_m": 4.0}}],
        "parts": [{"name": "surface", "material": "water"}],
        "transform": tf(l.pond.0[0], l.pond.0[1], (wl * 100.0).round() / 100.0, 0.0)
    }));
    // Cars in the main lot (3 rows), the church lot and along Main Street.
    let mut parked = Vec::new();
    let mut running = Vec::new();
    let mut k = 0usize;
    let mut car = |x: f64, y: f64, rot: f64, rng: &mut SplitMix64| {
        k += 1;
        if rng.random::<f64>() < 0.25 {
            return; // empty space
        }
        let t = tf(x, y, h(x, y), rot);
        if k.is_multiple_of(5) {
            running.push(t)
        } else {
            parked.push(t)
        }
    };
    for row in 0..3 {
        let y = -20.0 + 9.0 * row as f64;
        for c in 0..28 {
            let x = -85.0 + 6.2 * c as f64;
            car(x, y, if row % 2 == 0 { 90.0 } else { -90.0 }, &mut rng);
        }
    }
    for c in 0..12 {
        car(145.0 + 6.5 * c as f64, -85.0, 90.0, &mut rng);
    }
    for c in 0..10 {
        car(-280.0 + 55.0 * c as f64, -42.0, 0.0, &mut rng);
    }
    objects.push(json!({
        "name": "car_parked",
        "shapes": car_shapes(),
        "parts": car_parts(false),
        "instances": parked
    }));
    objects.push(json!({
        "name": "car_running",
        "description": "Cars with idling engines: the engine part generates heat",
        "shapes": car_shapes(),
        "parts": car_parts(true),
        "instances": running
    }));
    // An armoured vehicle parked on the bare lot east of the plant.
    let mut av = vec![
        json!({"box": {"size": [6.8, 3.2, 1.4], "max_edge_m": 0.5, "bottom": false}, "part": "hull",
               "transform": {"translate": [0.0, 0.0, 0.55]}}),
        json!({"box": {"size": [1.8, 3.0, 0.3], "max_edge_m": 0.5, "bottom": false}, "part": "engine_deck",
               "transform": {"translate": [-2.4, 0.0, 1.95]}}),
        json!({"cylinder": {"radius": 1.3, "height": 0.8, "segments": 16}, "part": "turret",
               "transform": {"translate": [0.6, 0.0, 1.95]}}),
        json!({"cylinder": {"radius": 0.09, "height": 4.5, "segments": 8}, "part": "turret",
               "transform": {"rotate_deg": [0.0, 90.0, 0.0], "translate": [1.8, 0.0, 2.35]}}),
    ];
    for i in 0..4 {
        for side in [-1.0, 1.0] {
            av.push(json!({"cylinder": {"radius": 0.55, "height": 0.4, "segments": 12}, "part": "wheels",
                "transform": {"rotate_deg": [90.0, 0.0, 0.0],
                              "translate": [-2.4 + 1.6 * i as f64, side * 1.6 + if side > 0.0 { 0.4 } else { 0.0 }, 0.55]}}));
        }
    }
    let (vx, vy) = (180.0, 70.0);
    objects.push(json!({
        "name": "armoured_vehicle",
        "description": "8x8 wheeled armoured vehicle, engine running",
        "shapes": av,
        "parts": [
            {"name": "hull", "material": "painted_steel", "thickness_m": 0.025},
            {"name": "engine_deck", "material": "painted_steel", "thickness_m": 0.015, "self_power_w_m2": 600.0},
            {"name": "turret", "material": "painted_steel", "thickness_m": 0.03},
            {"name": "wheels", "material": "rubber_tire"}
        ],
        "transform": tf(vx, vy, h(vx, vy), 35.0)
    }));
    json!({
        "$schema": "../scene.schema.json",
        "description": "Bundled default scene: a small industrial town after the Kodak Hawkeye plant area, Rochester NY. Generated by `irsig scene town` (src/scene/town.rs); edit the generator, not this file.",
        "site": {"latitude_deg": 43.16, "longitude_deg": -77.61, "altitude_m": 160.0, "utc_offset_hours": -4.0},
        "time": TOWN_TIME,
        "weather": {"file": "weather.csv"},
        "materials": ["../materials.json"],
        "objects": objects,
        "sensors": [
            {"type": "frame", "name": "oblique_lwir",
             "width": 640, "height": 512, "pixel_pitch_m": 15e-6, "focal_length_m": 0.025,
             "position": [0.0, -330.0, 300.0], "look_at": [0.0, 60.0, 5.0], "up": [0.0, 0.0, 1.0],
             "bands": [{"name": "LWIR", "response": [8.0, 12.0]}, {"name": "MWIR", "response": [3.0, 5.0]}],
             "oversample": 2},
            {"type": "line_scanner", "name": "airborne_scanner",
             "ifov_rad": 1.0e-3, "scan_angle_deg": 60.0, "samples_per_line": 1024, "lines": 1000,
             "scan_rate_hz": 100.0, "altitude_m": 600.0, "ground_speed_m_s": 60.0, "heading_deg": 0.0,
             "roll_deg": 0.0, "pitch_deg": 0.0, "yaw_deg": 0.0, "start": [0.0, -300.0],
             "bands": [{"name": "LWIR", "response": [8.0, 14.0]}]}
        ]
    })
}

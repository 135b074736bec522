//! The flux-tower reader (`irsig::weather::flux`): the two validation
//! datasets of `../shared/data/flux` load as their READMEs describe, their
//! energy balance closes as stated, and the naive baseline
//! "T_surface = T_air" on the second half of each 42-day subset is measured
//! (the bar a thermal model must beat, issue 16). Bad files give errors
//! naming file, line and column.

use std::path::Path;

use irsig::analysis::stats;
use irsig::weather::flux::{self, FluxDataset, FluxSite};

use crate::util;

fn bondville_subset() -> FluxDataset {
    let dir = util::shared_data("flux");
    flux::load(&dir.join("bondville_1998/bondville_1998_aug01-sep11.csv")).unwrap()
}

fn us_crt_subset() -> FluxDataset {
    let dir = util::shared_data("flux");
    flux::load(&dir.join("us-crt_2011/us-crt_2011_jul06-aug16.csv")).unwrap()
}

/// US-CRT's canopy heights, from its README (site metadata): 0.15 m on
/// 5 Jul, 0.45 m on 26 Jul, 0.975 m on 19 Aug 2011. No LAI is given.
fn us_crt_heights() -> irsig::material::Phenology {
    use irsig::material::{Phenology, PhenologyPoint};
    let pt = |date: &str, h: f64| PhenologyPoint {
        date: date.parse().unwrap(),
        canopy_height_m: Some(h),
        leaf_area_index: None,
    };
    Phenology::try_from(vec![
        pt("2011-07-05", 0.15),
        pt("2011-07-26", 0.45),
        pt("2011-08-19", 0.975),
    ])
    .unwrap()
}

/// The height of US-CRT's wind and air measurement, which its metadata does
/// not give, m: the neutral log law on its measured wind and friction
/// velocity over the README's canopy heights
/// ([`FluxDataset::log_law_wind_height_m`], the 42 days).
fn us_crt_measurement_height_m() -> f64 {
    let d = us_crt_subset();
    let h = us_crt_heights();
    d.log_law_wind_height_m(0..d.len(), |t| h.at(t.timestamp() as f64, 0.0, 0.0).0)
        .unwrap()
}

/// Percentage of gaps of `field` over the whole file.
fn gap_pct(d: &FluxDataset, field: impl Fn(&flux::FluxRecord) -> Option<f64>) -> f64 {
    100.0 * d.gaps(0..d.len(), field) as f64 / d.len() as f64
}

#[test]
#[ignore = "needs ../shared/data"]
fn bondville_subset_loads_as_its_readme_says() {
    let d = bondville_subset();
    assert_eq!(d.site(), FluxSite::Bondville1998);
    assert_eq!(d.len(), 2016, "42 days of 30-min rows");
    let r = d.records();
    // 1998-08-01 00:00 LST (UTC−6) → 1998-09-12 00:00 LST, interval starts.
    assert_eq!(r[0].start.to_rfc3339(), "1998-08-01T06:00:00+00:00");
    assert_eq!(r[2015].start.to_rfc3339(), "1998-09-12T05:30:00+00:00");
    assert_eq!(d.mid_interval(0).to_rfc3339(), "1998-08-01T00:15:00-06:00");
    // "only 1 H and 1 LE value missing"; the forcing is complete.
    let all = 0..d.len();
    assert_eq!(d.gaps(all.clone(), |r| r.sensible_heat_w_m2), 1);
    assert_eq!(d.gaps(all.clone(), |r| r.latent_heat_w_m2), 1);
    for (name, n) in [
        ("air T", d.gaps(all.clone(), |r| r.air_temperature_k)),
        ("RH", d.gaps(all.clone(), |r| r.relative_humidity)),
        ("p", d.gaps(all.clone(), |r| r.pressure_pa)),
        ("wind 10 m", d.gaps(all.clone(), |r| r.wind_speed_m_s)),
        ("SW↓", d.gaps(all.clone(), |r| r.global_horizontal_w_m2)),
        ("LW↓", d.gaps(all.clone(), |r| r.sky_longwave_w_m2)),
        ("Rn", d.gaps(all.clone(), |r| r.net_radiation_w_m2)),
        ("IRT", d.gaps(all.clone(), |r| r.surface_temperature_k)),
    ] {
        assert_eq!(n, 0, "{name} has {n} gaps");
    }
    let (w, fills) = d.weather(0..d.len()).unwrap();
    assert_eq!(w.records().len(), 2016);
    assert_eq!(fills.wind_interpolated, 0);
    assert_eq!(fills.pressure_interpolated, 0);
    println!("Bondville forcing adjustments: {fills:?}");
    // Weather at mid-interval; the Erbs split closes on the measured global.
    let rec = &w.records()[24]; // 12:15 LST on Aug 1
    assert_eq!(rec.time.to_rfc3339(), "1998-08-01T12:15:00-06:00");
    let sun = w.sun_position(rec.time).unwrap();
    let closure = rec.diffuse_horizontal_w_m2
        + rec.direct_normal_w_m2 * sun.apparent_zenith_deg.to_radians().cos();
    assert!(
        (closure - rec.global_horizontal_w_m2).abs() < 1e-6 * rec.global_horizontal_w_m2.max(1.0),
        "{closure} vs {}",
        rec.global_horizontal_w_m2
    );
}

#[test]
#[ignore = "needs ../shared/data"]
fn us_crt_subset_loads_as_its_readme_says() {
    let d = us_crt_subset();
    assert_eq!(d.site(), FluxSite::UsCrt2011);
    assert_eq!(d.len(), 2016);
    let r = d.records();
    // 2011-07-06 00:00 LST (UTC−5).
    assert_eq!(r[0].start.to_rfc3339(), "2011-07-06T05:00:00+00:00");
    assert_eq!(r[2015].start.to_rfc3339(), "2011-08-17T04:30:00+00:00");
    // "WS/PA missing 20.6 %, H 20.8 %, LE 29.1 %; everything else is complete."
    let pct = |f: fn(&flux::FluxRecord) -> Option<f64>| gap_pct(&d, f);
    for (name, got, readme) in [
        ("WS", pct(|r| r.wind_speed_m_s), 20.6),
        ("PA", pct(|r| r.pressure_pa), 20.6),
        ("H", pct(|r| r.sensible_heat_w_m2), 20.8),
        ("LE", pct(|r| r.latent_heat_w_m2), 29.1),
        ("TA", pct(|r| r.air_temperature_k), 0.0),
        ("RH", pct(|r| r.relative_humidity), 0.0),
        ("SW_IN", pct(|r| r.global_horizontal_w_m2), 0.0),
        ("LW_IN", pct(|r| r.sky_longwave_w_m2), 0.0),
        ("LW_OUT", pct(|r| r.longwave_up_w_m2), 0.0),
        ("NETRAD", pct(|r| r.net_radiation_w_m2), 0.0),
        ("G", pct(|r| r.ground_heat_w_m2), 0.0),
    ] {
        assert!(
            (got - readme).abs() <= 0.05,
            "{name}: {got:.2} % missing, README {readme} %"
        );
    }
    // Surface temperature from LW with ε = 0.98: "a range of 10.4–43.3 °C".
    let ts: Vec<f64> = r.iter().filter_map(|r| r.surface_temperature_k).collect();
    assert_eq!(ts.len(), 2016);
    let (lo, hi) = ts
        .iter()
        .fold((f64::MAX, f64::MIN), |(a, b), &t| (a.min(t), b.max(t)));
    assert!(((lo - 273.15) - 10.4).abs() < 0.05, "min {}", lo - 273.15);
    assert!(((hi - 273.15) - 43.3).abs() < 0.05, "max {}", hi - 273.15);
    // The forcing: wind and pressure gaps interpolated, the rest complete.
    let (w, fills) = d.weather(0..d.len()).unwrap();
    assert_eq!(w.records().len(), 2016);
    assert_eq!(
        fills.wind_interpolated,
        d.gaps(0..d.len(), |r| r.wind_speed_m_s)
    );
    assert_eq!(
        fills.pressure_interpolated,
        d.gaps(0..d.len(), |r| r.pressure_pa)
    );
    println!("US-CRT forcing adjustments: {fills:?}");
}

#[test]
#[ignore = "needs ../shared/data"]
fn full_years_load_with_the_readme_gap_fractions() {
    let dir = util::shared_data("flux");
    let b = flux::load(&dir.join("bondville_1998/bondville_1998_full_year.csv")).unwrap();
    assert_eq!(b.len(), 17520);
    // "H 10 %, LE 21 %, IRT 4.7 %"; forcing 100 % present.
    for (name, got, readme, tol) in [
        ("H", gap_pct(&b, |r| r.sensible_heat_w_m2), 10.0, 0.5),
        ("LE", gap_pct(&b, |r| r.latent_heat_w_m2), 21.0, 0.5),
        ("IRT", gap_pct(&b, |r| r.surface_temperature_k), 4.7, 0.05),
        ("T", gap_pct(&b, |r| r.air_temperature_k), 0.0, 0.0),
        ("wind 10 m", gap_pct(&b, |r| r.wind_speed_m_s), 0.0, 0.0),
    ] {
        assert!(
            (got - readme).abs() <= tol,
            "Bondville {name}: {got:.2} %, README {readme} %"
        );
    }
    let c = flux::load(&dir.join("us-crt_2011/us-crt_2011_full_year.csv")).unwrap();
    assert_eq!(c.len(), 17520);
    // "WS, PA missing 34 %, H 35 %, LE 47 %, RH 2.8 %".
    for (name, got, readme, tol) in [
        ("WS", gap_pct(&c, |r| r.wind_speed_m_s), 34.0, 0.5),
        ("PA", gap_pct(&c, |r| r.pressure_pa), 34.0, 0.5),
        ("H", gap_pct(&c, |r| r.sensible_heat_w_m2), 35.0, 0.5),
        ("LE", gap_pct(&c, |r| r.latent_heat_w_m2), 47.0, 0.5),
        ("RH", gap_pct(&c, |r| r.relative_humidity), 2.8, 0.05),
    ] {
        assert!(
            (got - readme).abs() <= tol,
            "US-CRT {name}: {got:.2} %, README {readme} %"
        );
    }
    // A humidity gap in the forcing is an error naming the line and column.
    let first_gap = c
        .records()
        .iter()
        .position(|r| r.relative_humidity.is_none())
        .unwrap();
    let e = c
        .weather(first_gap.saturating_sub(2)..first_gap + 2)
        .unwrap_err()
        .to_string();
    assert!(
        e.contains(&format!("line {}", c.records()[first_gap].line))
            && e.contains("relative_humidity_pct"),
        "{e}"
    );
}

#[test]
#[ignore = "needs ../shared/data"]
fn energy_balance_closure_is_as_the_readmes_say() {
    // Daytime (SW↓ > 20 W/m²) Σ(H + LE)/Σ(Rn − G): README 0.86 (Bondville
    // subset), 0.91 (US-CRT subset); their "daytime" may differ slightly.
    for (d, readme) in [(bondville_subset(), 0.86), (us_crt_subset(), 0.91)] {
        let c = d.energy_balance_closure(0..d.len(), 20.0);
        println!(
            "{:?}: closure Σ(H+LE)/Σ(Rn−G) = {:.3} over {} daytime records; slope {:.3}, \
             intercept {:.1} W/m², mean residual Rn−G−H−LE {:.1} W/m²",
            d.site(),
            c.ratio_of_sums,
            c.records,
            c.slope,
            c.intercept_w_m2,
            c.mean_residual_w_m2
        );
        assert!(c.records > 900, "{}", c.records);
        assert!(
            (c.ratio_of_sums - readme).abs() < 0.03,
            "{} vs {readme}",
            c.ratio_of_sums
        );
        assert!(
            c.mean_residual_w_m2 > 0.0,
            "an open balance: turbulent fluxes short"
        );
    }
}

#[test]
#[ignore = "needs ../shared/data"]
fn baseline_surface_temperature_equals_air_temperature() {
    // The naive model T_s = T_air on the second half (days 22–42) of each
    // subset: the numbers a thermal model must beat (model − measured).
    for d in [bondville_subset(), us_crt_subset()] {
        let (model, truth): (Vec<f64>, Vec<f64>) = d.records()[d.second_half()]
            .iter()
            .filter_map(|r| Some((r.air_temperature_k?, r.surface_temperature_k?)))
            .unzip();
        assert_eq!(model.len(), 1008);
        let rmse = stats::rmse(&model, &truth).unwrap();
        let bias = stats::bias(&model, &truth).unwrap();
        let rho = stats::spearman(&model, &truth).unwrap();
        println!(
            "{:?} ({}), T_s = T_air on the second half: RMSE {rmse:.2} K, bias {bias:+.2} K, \
             Spearman {rho:.3} (n = {})",
            d.site(),
            d.site().surface_temperature_source(),
            model.len()
        );
        assert!((1.0..4.0).contains(&rmse), "RMSE {rmse}");
        assert!(bias.abs() < 2.0, "bias {bias}");
        assert!(rho > 0.8, "Spearman {rho}");
    }
}

const HEADER: &str = "time_utc,air_temperature_c,relative_humidity_pct,pressure_hpa,\
wind_speed_10m_m_s,wind_direction_10m_deg,wind_speed_6m_m_s,sw_down_w_m2,lw_down_w_m2,\
net_radiation_w_m2,surface_temperature_c,sensible_heat_w_m2,latent_heat_w_m2,\
ground_heat_w_m2,precipitation_mm";

fn parse(rows: &[&str]) -> irsig::error::Result<FluxDataset> {
    let text = format!("{HEADER}\n{}\n", rows.join("\n"));
    flux::from_reader(
        text.as_bytes(),
        Path::new("tower.csv"),
        flux::CROP_EMISSIVITY,
    )
}

const ROW0: &str = "1998-08-01T18:00:00Z,25,60,990,3,180,3,600,380,400,28,100,200,50,0";
const ROW1: &str = "1998-08-01T18:30:00Z,25.5,58,990,3.2,180,3,610,380,410,28.5,110,210,50,0";

#[test]
fn a_small_file_parses_and_becomes_weather() {
    let d = parse(&[ROW0, ROW1]).unwrap();
    assert_eq!(d.site(), FluxSite::Bondville1998);
    let r = &d.records()[1];
    assert_eq!(r.line, 3);
    assert!((r.surface_temperature_k.unwrap() - 301.65).abs() < 1e-9);
    assert_eq!(r.residual_w_m2(), Some(410.0 - 50.0 - 110.0 - 210.0));
    let (w, _) = d.weather(0..2).unwrap();
    assert_eq!(
        w.records()[0].time.to_rfc3339(),
        "1998-08-01T12:15:00-06:00"
    );
    assert!(w.records()[0].direct_normal_w_m2 > 0.0);
}

#[test]
fn bad_cells_are_errors_naming_file_line_and_column() {
    let bad = ROW1.replace("25.5", "warm");
    let e = parse(&[ROW0, &bad]).unwrap_err().to_string();
    assert!(
        e.contains("tower.csv") && e.contains("line 3") && e.contains("air_temperature_c"),
        "{e}"
    );
    let late = ROW1.replace("18:30", "19:30");
    let e = parse(&[ROW0, &late]).unwrap_err().to_string();
    assert!(
        e.contains("line 3") && e.contains("time_utc") && e.contains("1800 s"),
        "{e}"
    );
    let e = flux::from_reader(&b"a,b\n1,2\n"[..], Path::new("other.csv"), 0.98)
        .unwrap_err()
        .to_string();
    assert!(e.contains("other.csv") && e.contains("line 1"), "{e}");
    // A gap in a forcing column that is never filled.
    let gap = ROW1.replace(",380,410", ",,410");
    let d = parse(&[ROW0, &gap]).unwrap();
    let e = d.weather(0..2).unwrap_err().to_string();
    assert!(e.contains("line 3") && e.contains("lw_down_w_m2"), "{e}");
    // Wind with no value at all cannot be interpolated.
    let calm0 = ROW0.replace(",3,180,3,", ",,180,3,");
    let calm1 = ROW1.replace(",3.2,180,3,", ",,180,3,");
    let e = parse(&[&calm0, &calm1])
        .unwrap()
        .weather(0..2)
        .unwrap_err()
        .to_string();
    assert!(e.contains("wind_speed_10m_m_s"), "{e}");
    let e = flux::from_reader(&b""[..], Path::new("x.csv"), 1.5)
        .unwrap_err()
        .to_string();
    assert!(e.contains("emissivity"), "{e}");
}

#[test]
#[ignore = "needs ../shared/data"]
fn penman_monteith_on_measured_available_energy() {
    // A first look at the latent physics on real forcing, before it is in
    // the thermal model: big-leaf Penman–Monteith (FAO-56 eq. 3) with the
    // *measured* Rn − G, r_a from the wind (FAO-56 eq. 4, Louis stability at
    // the measured surface temperature) and a Jarvis–Stewart r_s with
    // Noilhan & Planton's crop values, against the measured LE on the
    // daytime records of each second half. Not fitted: canopy heights are
    // the READMEs' (US-CRT: 0.45 m on 26 Jul, 0.975 m on 19 Aug → 0.7 m) or
    // assumed (Bondville, undocumented: 0.8 m), as are the LAI (3) and an
    // unstressed soil; US-CRT's undocumented sensor height is the log law's
    // on its own wind and u* (2.7 m). Also the same with r_s = 0: the
    // wet-surface rate, the most a canopy transpires on that energy.
    use irsig::thermal::latent::penman_monteith_latent_w_m2;
    use irsig::thermal::latent::{Aerodynamic, AirState, CanopyConditions, JarvisStewart};
    let mut ratios = Vec::new();
    let mut wet_fractions = Vec::new();
    let z_crt = us_crt_measurement_height_m();
    for (d, canopy_m) in [(bondville_subset(), 0.8), (us_crt_subset(), 0.7)] {
        let site = d.site();
        let aero = Aerodynamic::from_canopy_height(
            canopy_m,
            site.wind_height_m().unwrap_or(z_crt),
            site.air_height_m().unwrap_or(z_crt),
        )
        .unwrap();
        let canopy = JarvisStewart {
            min_stomatal_resistance_s_m: 40.0,
            max_stomatal_resistance_s_m: 5000.0,
            leaf_area_index: 3.0,
            shortwave_limit_w_m2: 30.0,
            vpd_sensitivity_per_pa: 0.0,
            optimum_temperature_k: 298.0,
            temperature_sensitivity_per_k2: 0.0016,
            wilting_point_m3_m3: 0.1,
            field_capacity_m3_m3: 0.3,
        };
        canopy.validate().unwrap();
        let half = d.second_half();
        let (w, _) = d.weather(half.clone()).unwrap();
        let (mut model, mut measured, mut closed, mut wet) = (0.0, 0.0, 0.0, 0.0);
        let mut n = 0;
        for (r, wr) in d.records()[half].iter().zip(w.records()) {
            let (Some(rn), Some(g), Some(h), Some(le), Some(ts)) = (
                r.net_radiation_w_m2,
                r.ground_heat_w_m2,
                r.sensible_heat_w_m2,
                r.latent_heat_w_m2,
                r.surface_temperature_k,
            ) else {
                continue;
            };
            if wr.global_horizontal_w_m2 <= 20.0 {
                continue;
            }
            let air = AirState::from_relative_humidity(
                wr.air_temperature_k,
                wr.relative_humidity,
                wr.pressure_pa,
            )
            .unwrap();
            let r_a = aero.resistance_s_m(wr.wind_speed_m_s, ts, wr.air_temperature_k);
            let r_s = canopy.surface_resistance_s_m(&CanopyConditions {
                shortwave_down_w_m2: wr.global_horizontal_w_m2,
                vapour_pressure_deficit_pa: air.vapour_pressure_deficit_pa(),
                air_temperature_k: wr.air_temperature_k,
                soil_moisture_m3_m3: 0.3,
            });
            model += penman_monteith_latent_w_m2(rn - g, &air, r_a, r_s).unwrap();
            wet += penman_monteith_latent_w_m2(rn - g, &air, r_a, 0.0).unwrap();
            measured += le;
            // LE with the balance closed at the measured Bowen ratio.
            if h + le != 0.0 {
                closed += le * (rn - g) / (h + le);
            }
            n += 1;
        }
        let (model, measured, closed) = (model / n as f64, measured / n as f64, closed / n as f64);
        let wet = wet / n as f64;
        println!(
            "{site:?}: daytime mean LE of a wet surface (r_s = 0) {wet:.0} W/m²; measured / wet \
             {:.2} (Bowen-closed {:.2})",
            measured / wet,
            closed / wet
        );
        println!(
            "{site:?}: daytime mean LE, Penman–Monteith {model:.0} W/m², measured {measured:.0} \
             W/m² (Bowen-closed {closed:.0}); ratio {:.2} ({:.2} closed), n = {n}",
            model / measured,
            model / closed
        );
        ratios.push((site, n, model / measured));
        wet_fractions.push(closed / wet);
    }
    // Measured (closure-corrected) LE as a fraction of the wet-surface
    // rate: US-CRT's soybean, on a wet soil after the rain of late July,
    // evaporated at 0.87 of it, Bondville's in late August at 0.68. One
    // canopy resistance cannot give both (docs/physics/validation.md).
    assert!(
        wet_fractions[1] - wet_fractions[0] > 0.1,
        "measured / wet-surface LE: Bondville {}, US-CRT {}",
        wet_fractions[0],
        wet_fractions[1]
    );
    // The canopy here is unstressed (no VPD or soil-water limitation), so
    // this is a potential rate: not below the measured one, and within a
    // factor of two of it. (Bondville, late summer 1998: 1.5.)
    for (site, n, ratio) in ratios {
        assert!(n > 400, "{site:?}: {n} records");
        assert!(
            (0.9..2.0).contains(&ratio),
            "{site:?}: PM / measured LE = {ratio}"
        );
    }
}

/// What a stock material gives on one site's second half.
struct StockResult {
    rmse: f64,
    /// A two-source canopy: RMSE and bias of its hemispherical composite
    /// (the temperature LW↑ gives), K.
    rmse_hemispherical: Option<(f64, f64)>,
    bias: f64,
    spearman: f64,
    air_rmse: f64,
    by_hour: [f64; 24],
    /// Daytime means (global SW > 20 W/m², records with both measured):
    /// (modelled LE, measured LE, modelled H, measured H), W/m².
    day_fluxes: (f64, f64, f64, f64),
    /// Daytime means over the same records, W/m²: measured H and LE with
    /// the energy-balance residual shared at the measured Bowen ratio
    /// (`H·(Rn − G)/(H + LE)`, the closure-corrected fluxes; records with
    /// measured Rn and G), the model's H at the *measured* surface
    /// temperature (`h·(T_meas − T_air)`, the model's own exchange), the
    /// modelled and measured G and net radiation.
    day_closed: DayClosed,
    n: usize,
    /// The root zone's water content at each record, m³ m⁻³ (empty: θ
    /// constant).
    soil_moisture: Vec<f64>,
}

/// Daytime means of [`StockResult::day_closed`], W/m².
#[derive(Debug, Default)]
struct DayClosed {
    h_closed: f64,
    /// H with the whole residual given to it, `Rn − G − LE` (the
    /// non-closure as missing sensible heat).
    h_residual: f64,
    le_closed: f64,
    h_model_at_measured_t: f64,
    g_model: f64,
    g_measured: f64,
    rn_model: f64,
    rn_measured: f64,
}

/// The stock material `name` of `scenes/materials.json` with its `surface_energy` block changed by
/// `edit`.
fn stock_props_with(
    name: &str,
    edit: impl FnOnce(&mut irsig::material::SurfaceEnergySpec),
) -> irsig::thermal::SlabProperties {
    let db = irsig::material::stock::stock().unwrap();
    let mut m = db.get(name).unwrap().clone();
    edit(m.surface_energy.as_mut().unwrap());
    irsig::thermal::SlabProperties::from_material(&m).unwrap()
}

/// The site's measured soil water content at each record, m³ m⁻³: the
/// mean of Bondville's 5, 20 and 60 cm probes (a 1 m root zone's), US-CRT's
/// SWC (one probe; its README gives no depth). None where missing.
fn measured_soil_water(d: &FluxDataset) -> Vec<Option<f64>> {
    let (file, cols, scale): (&str, &[&str], f64) = match d.site() {
        FluxSite::Bondville1998 => (
            "bondville_1998/bondville_1998_aug01-sep11.csv",
            &[
                "soil_moisture_m3_m3_at_5cm",
                "soil_moisture_m3_m3_at_20cm",
                "soil_moisture_m3_m3_at_60cm",
            ],
            1.0,
        ),
        _ => (
            "us-crt_2011/us-crt_2011_jul06-aug16.csv",
            &["soil_water_content_pct"],
            0.01,
        ),
    };
    let mut r = csv::Reader::from_path(util::shared_data("flux").join(file)).unwrap();
    let idx: Vec<usize> = cols
        .iter()
        .map(|c| r.headers().unwrap().iter().position(|h| h == *c).unwrap())
        .collect();
    let v: Vec<Option<f64>> = r
        .records()
        .map(|row| {
            let row = row.unwrap();
            let vals: Option<Vec<f64>> = idx
                .iter()
                .map(|&i| row.get(i)?.parse::<f64>().ok())
                .collect();
            vals.map(|v| scale * v.iter().sum::<f64>() / v.len() as f64)
        })
        .collect();
    assert_eq!(v.len(), d.len(), "one row per record");
    v
}

/// The material `props` (a horizontal facet open to the whole sky) driven
/// by the site's 42-day forcing, compared with the measured surface
/// temperature and fluxes on the second half (model − measured).
fn props_on_site(props: &irsig::thermal::SlabProperties, d: &FluxDataset) -> StockResult {
    use irsig::analysis::facet::{FacetSpec, solve_free_facet};
    use irsig::thermal::latent::psychrometrics::saturation_vapour_pressure_pa;
    use irsig::thermal::{Exchange, Forcing, STEFAN_BOLTZMANN_W_M2_K4, SolveOptions};

    let props = *props;
    let (history, _) = d.weather(0..d.len()).unwrap();
    let site = d.site().site();
    let (sol, _) = solve_free_facet(
        &props,
        history.records(),
        &site,
        &FacetSpec::default(),
        &SolveOptions::default(),
    )
    .unwrap();
    let forcing = Forcing::from_records(history.records()).unwrap();
    let ex = Exchange::new(&props, &forcing).unwrap();
    let (mut model, mut truth, mut air) = (Vec::new(), Vec::new(), Vec::new());
    let mut by_hour = [(0.0f64, 0usize); 24];
    let (mut le_m, mut le_o, mut h_m, mut h_o, mut nd) = (0.0, 0.0, 0.0, 0.0, 0usize);
    let mut dc = DayClosed::default();
    let mut nc = 0usize;
    // A two-source canopy: its fluxes at record i (the open facet's
    // source is α·global + ε·LW↓) as (Rn, H, LE, G), and the hemispherical
    // composite of leaves and soil (what LW↑ sees).
    let two = |i: usize| {
        ex.two_source.get(i).map(|step| {
            let w = &history.records()[i];
            let s = props.solar_absorptivity * w.global_horizontal_w_m2
                + props.thermal_emissivity * w.sky_longwave_w_m2;
            let f = step.fluxes(s, sol.soil_temperature_k[i]);
            (
                (
                    f.net_radiation_w_m2(),
                    f.sensible_w_m2(),
                    f.latent_w_m2(),
                    f.ground_w_m2,
                ),
                step.hemispherical_k(s, sol.soil_temperature_k[i]),
            )
        })
    };
    let mut hemi = Vec::new();
    for i in d.second_half() {
        let r = &d.records()[i];
        let w = &history.records()[i];
        let t_s = sol.surface_temperature_k[i];
        assert!(t_s.is_finite());
        if let (Some(le), Some(h)) = (r.latent_heat_w_m2, r.sensible_heat_w_m2)
            && w.global_horizontal_w_m2 > 20.0
        {
            if let Some(((_, h2, le2, _), _)) = two(i) {
                le_m += le2;
                h_m += h2;
            } else {
                le_m += ex.vapour_conductance_w_m2_pa[i]
                    * (saturation_vapour_pressure_pa(t_s) - forcing.vapour_pressure_pa[i]);
                h_m += ex.sensible_w_m2_k[i] * (t_s - w.air_temperature_k);
            }
            le_o += le;
            h_o += h;
            nd += 1;
            if let (Some(rn), Some(g), Some(t_meas)) = (
                r.net_radiation_w_m2,
                r.ground_heat_w_m2,
                r.surface_temperature_k,
            ) {
                let eps = props.thermal_emissivity;
                let (rn_k, h_k, le_k) = match two(i) {
                    Some(((rn2, h2, le2, _), _)) => (rn2, h2, le2),
                    None => (
                        props.solar_absorptivity * w.global_horizontal_w_m2
                            + eps * (w.sky_longwave_w_m2 - STEFAN_BOLTZMANN_W_M2_K4 * t_s.powi(4)),
                        ex.sensible_w_m2_k[i] * (t_s - w.air_temperature_k),
                        ex.vapour_conductance_w_m2_pa[i]
                            * (saturation_vapour_pressure_pa(t_s) - forcing.vapour_pressure_pa[i]),
                    ),
                };
                let bowen = if h + le != 0.0 {
                    (rn - g) / (h + le)
                } else {
                    1.0
                };
                dc.h_closed += h * bowen;
                dc.h_residual += rn - g - le;
                dc.le_closed += le * bowen;
                dc.h_model_at_measured_t += ex.sensible_w_m2_k[i] * (t_meas - w.air_temperature_k);
                dc.g_model += rn_k - h_k - le_k;
                dc.g_measured += g;
                dc.rn_model += rn_k;
                dc.rn_measured += rn;
                nc += 1;
            }
        }
        let Some(t) = r.surface_temperature_k else {
            continue;
        };
        model.push(t_s);
        if let Some((_, t_h)) = two(i) {
            hemi.push(t_h);
        }
        truth.push(t);
        air.push(w.air_temperature_k);
        let hour = chrono::Timelike::hour(&w.time) as usize;
        by_hour[hour].0 += t_s - t;
        by_hour[hour].1 += 1;
    }
    let nd = nd.max(1) as f64;
    let nc = nc.max(1) as f64;
    for v in [
        &mut dc.h_closed,
        &mut dc.h_residual,
        &mut dc.le_closed,
        &mut dc.h_model_at_measured_t,
        &mut dc.g_model,
        &mut dc.g_measured,
        &mut dc.rn_model,
        &mut dc.rn_measured,
    ] {
        *v /= nc;
    }
    StockResult {
        rmse_hemispherical: (!hemi.is_empty()).then(|| {
            (
                stats::rmse(&hemi, &truth).unwrap(),
                stats::bias(&hemi, &truth).unwrap(),
            )
        }),
        day_closed: dc,
        rmse: stats::rmse(&model, &truth).unwrap(),
        bias: stats::bias(&model, &truth).unwrap(),
        spearman: stats::spearman(&model, &truth).unwrap(),
        air_rmse: stats::rmse(&air, &truth).unwrap(),
        by_hour: by_hour.map(|(s, n)| s / n.max(1) as f64),
        day_fluxes: (le_m / nd, le_o / nd, h_m / nd, h_o / nd),
        n: model.len(),
        soil_moisture: ex.soil_moisture_m3_m3.clone(),
    }
}

/// The thermal model on measured forcing, as a user would validate it: the
/// stock `crop` (a closed field crop, the surface of both sites: soybean)
/// and `grass`, uncalibrated; each also with kB⁻¹ from its canopy
/// (`su2001`); as two sources; at US-CRT the crop growing to the README's
/// heights, with its leaves growing with them (LAI = min(6.8 h, LAI)); and,
/// as diagnostics of the partition, the crop with r_s,min = 40 s/m, the
/// growing two-source crop with LAI 5, with US-CRT's measured soil
/// water and the porosity of its silty clay, and with Noah's cropland
/// stomata (big leaf and two sources). US-CRT's materials are given its
/// log-law measurement height. Printed for the validation page
/// (`docs/physics/validation.md`).
/// Asserted: the stock crop, with either heat roughness and growing,
/// beats the naive "T_surface = T_air" on both sites (issue 16's goal for
/// stock materials), and its daytime latent heat is the larger turbulent
/// flux, as measured over these canopies; as two sources it meets issue
/// 16's flux goals at Bondville (H within 30 %, LE within 25 % of the
/// closure-corrected means) and the LE goal at US-CRT.
#[test]
#[ignore = "needs ../shared/data"]
fn stock_materials_on_measured_forcing() {
    use irsig::material::HeatRoughness;
    let grow = |s: &mut irsig::material::SurfaceEnergySpec| {
        s.phenology = us_crt_heights();
    };
    // Where US-CRT's wind and air were measured (its metadata does not say;
    // the log law on its own wind and u* gives it): the user tells the
    // material (`measurement_height_m`). Bondville's are the weather's
    // defaults (wind 10 m; air 3 m, the 2 m raised to 2 m above the canopy).
    let us_crt_z = us_crt_measurement_height_m();
    println!("US-CRT wind and air height from the log law: {us_crt_z:.2} m");
    // US-CRT's measured soil water (the first half's mean of its SWC
    // column, %), for the variant given the site's soil state.
    let us_crt_soil_water = {
        let path = util::shared_data("flux").join("us-crt_2011/us-crt_2011_jul06-aug16.csv");
        let mut r = csv::Reader::from_path(path).unwrap();
        let col = r
            .headers()
            .unwrap()
            .iter()
            .position(|h| h == "soil_water_content_pct")
            .unwrap();
        let v: Vec<f64> = r
            .records()
            .take(us_crt_subset().first_half().len())
            .filter_map(|row| row.unwrap().get(col)?.parse::<f64>().ok())
            .collect();
        v.iter().sum::<f64>() / v.len() as f64 / 100.0
    };
    for d in [bondville_subset(), us_crt_subset()] {
        let us_crt = d.site() == FluxSite::UsCrt2011;
        for name in [
            "crop",
            "grass",
            "crop su2001",
            "grass su2001",
            "crop growing",
            "crop growing su2001",
            "crop rsmin40",
            "crop two_source",
            "grass two_source",
            "crop growing two_source",
            "crop growing leafgrowth",
            "crop growing leafgrowth two_source",
            "crop growing leafgrowth lai5 two_source",
            "crop growing two_source swc",
            "crop noah",
            "crop noah two_source",
            "crop water",
            "grass water",
            "crop water measured",
        ] {
            if (name.contains("growing") || name.contains("swc")) && !us_crt {
                continue;
            }
            let stock = name.split(' ').next().unwrap();
            let r = props_on_site(
                &stock_props_with(stock, |s| {
                    if us_crt {
                        s.measurement_height_m = Some(us_crt_z);
                    }
                    if name.contains("su2001") {
                        s.heat_roughness = HeatRoughness::Su2001;
                    }
                    if name.contains("growing") {
                        grow(s);
                    }
                    // Leaves that grow with the height up to the stock LAI:
                    // METRIC's field-crop 6.8 m⁻¹ (materials docs).
                    if name.contains("leafgrowth") {
                        s.leaf_area_per_height_per_m = Some(6.8);
                    }
                    // A diagnostic, not a stock value: a closed soybean
                    // canopy of LAI 5 instead of the stock crop's 3.
                    if name.contains("lai5") {
                        s.leaf_area_index = 5.0;
                    }
                    // The site's soil state instead of the stock loam's: its
                    // measured soil water and the porosity of its silty clay
                    // (0.492, Clapp & Hornberger 1978 Table 2).
                    if name.contains("swc") {
                        s.soil_moisture_m3_m3 = us_crt_soil_water;
                        s.saturation_m3_m3 = Some(0.492);
                        println!("US-CRT first-half soil water {us_crt_soil_water:.3} m³/m³");
                    }
                    // A diagnostic, not a stock value: the crop r_s,min of
                    // Noilhan & Planton (1989) and Noah's cropland table.
                    if name.contains("rsmin40") {
                        s.min_stomatal_resistance_s_m = 40.0;
                    }
                    // A diagnostic, not a stock value: Noah's cropland
                    // stomata (VEGPARM.TBL, Chen & Dudhia 2001: RS 40 s/m,
                    // RGL 100 W/m², HS 36.25 (kg/kg)⁻¹; HS in NP89's linear
                    // form, its first order: 36.25 · 0.622 / 1e5 Pa⁻¹).
                    if name.contains("noah") {
                        s.min_stomatal_resistance_s_m = 40.0;
                        s.shortwave_limit_w_m2 = Some(100.0);
                        s.vpd_sensitivity_per_pa = 36.25 * 0.622 / 1e5;
                    }
                    if name.contains("two_source") {
                        s.canopy = irsig::material::CanopyModel::TwoSource;
                    }
                    // The root-zone water budget: 1 m, FAO-56 Table 22's
                    // rooting depth of soybean (0.6–1.3 m) and grass
                    // (0.5–1.5 m); "measured": starting from the site's
                    // first measured soil water and its soil's porosity.
                    if name.contains("water") {
                        s.root_zone_depth_m = Some(1.0);
                        if name.contains("measured") {
                            s.soil_moisture_m3_m3 = measured_soil_water(&d)[0].unwrap();
                            s.saturation_m3_m3 = Some(if us_crt { 0.492 } else { 0.451 });
                        }
                    }
                }),
                &d,
            );
            let hours: Vec<String> = r.by_hour.iter().map(|v| format!("{v:+.1}")).collect();
            let (le_m, le_o, h_m, h_o) = r.day_fluxes;
            println!(
                "{:?}: stock {name}, horizontal, F = 1, second half: RMSE {:.2} K (T_air {:.2} K), \
                 bias {:+.2} K, Spearman {:.3} (n = {}); daytime LE {le_m:.0} vs measured {le_o:.0} \
                 W/m², H {h_m:.0} vs {h_o:.0} W/m²; mean residual by local standard hour 0..23: {}",
                d.site(),
                r.rmse,
                r.air_rmse,
                r.bias,
                r.spearman,
                r.n,
                hours.join(" ")
            );
            if !r.soil_moisture.is_empty() {
                let measured = measured_soil_water(&d);
                let (mut m, mut o) = (Vec::new(), Vec::new());
                for i in d.second_half() {
                    if let Some(t) = measured[i] {
                        m.push(r.soil_moisture[i]);
                        o.push(t);
                    }
                }
                let first = d.second_half().start;
                println!(
                    "{:?}: stock {name}: root-zone θ second half RMSE {:.3} m³/m³ vs measured \
                     (n = {}); θ model {:.3} → {:.3}, measured {:.3} → {:.3}",
                    d.site(),
                    stats::rmse(&m, &o).unwrap(),
                    m.len(),
                    r.soil_moisture[first],
                    r.soil_moisture[d.len() - 1],
                    o[0],
                    o[o.len() - 1]
                );
                assert!(
                    r.soil_moisture.iter().all(|t| (0.0..=0.5).contains(t)),
                    "θ within the bucket"
                );
                // Both sites' soils dry over their second halves; the
                // bucket dries with them.
                assert!(o[o.len() - 1] < o[0], "measured θ falls");
                assert!(
                    r.soil_moisture[d.len() - 1] < r.soil_moisture[first],
                    "{:?}: modelled θ falls",
                    d.site()
                );
            }
            if let Some((rmse, bias)) = r.rmse_hemispherical {
                println!(
                    "{:?}: stock {name}: hemispherical composite RMSE {rmse:.2} K, bias {bias:+.2} K",
                    d.site()
                );
            }
            let c = &r.day_closed;
            // A two-source canopy has no single exchange coefficient to
            // apply to the measured temperature.
            let h_at_measured = if r.rmse_hemispherical.is_some() {
                "—".to_string()
            } else {
                format!("{:.0}", c.h_model_at_measured_t)
            };
            println!(
                "{:?}: stock {name}, daytime: H closure-corrected (Bowen) {:.0} W/m² (the whole \
                 residual to H: {:.0}), LE closure-corrected {:.0}; model H at the measured surface temperature \
                 {h_at_measured}; G model {:.0} vs measured {:.0}; Rn model {:.0} vs measured \
                 {:.0} W/m²",
                d.site(),
                c.h_closed,
                c.h_residual,
                c.le_closed,
                c.g_model,
                c.g_measured,
                c.rn_model,
                c.rn_measured
            );
            // Issue 16's flux goals where the stock crop as two sources
            // meets them: daytime H within 30 % and LE within 25 % of the
            // closure-corrected means at Bondville, LE at US-CRT (its H is
            // not met: docs/physics/validation.md).
            if name == "crop two_source" {
                let le_err = le_m / c.le_closed - 1.0;
                assert!(
                    le_err.abs() < 0.25,
                    "{:?}: LE {le_m} vs {}",
                    d.site(),
                    c.le_closed
                );
                if !us_crt {
                    let h_err = h_m / c.h_closed - 1.0;
                    assert!(
                        h_err.abs() < 0.30,
                        "{:?}: H {h_m} vs {}",
                        d.site(),
                        c.h_closed
                    );
                }
            }
            if name.starts_with("crop") && !name.contains("rsmin40") && !name.contains("noah") {
                assert!(
                    r.rmse < r.air_rmse,
                    "{:?}: stock crop RMSE {} K does not beat T_air {} K",
                    d.site(),
                    r.rmse,
                    r.air_rmse
                );
                assert!(le_m > h_m, "{:?}: LE {le_m} H {h_m}", d.site());
            }
        }
    }
}

/// Where the stock crop's daytime energy goes as two sources, by local
/// standard hour over each second half (records with measured H, LE, Rn, G
/// and surface temperature, global SW > 20 W/m²): the leaves' and the
/// soil's H, LE and Rn, the soil's G, against the closure-corrected (Bowen)
/// measured H and LE, Rn and the plates' G; the leaves', the soil's and the
/// measured radiometric temperature above the air; the resistances r_a,
/// r_x, r_st, r_soil, r_ss. US-CRT at its log-law measurement height.
/// Printed for the validation page; asserted: the leaves' balance closes at
/// every record, and at US-CRT most of the model's daytime H is the
/// leaves' (the soil's is a sixth).
#[test]
#[ignore = "needs ../shared/data"]
fn two_source_partition_by_hour() {
    use irsig::analysis::facet::{FacetSpec, solve_free_facet};
    use irsig::thermal::latent::AirState;
    use irsig::thermal::latent::psychrometrics::AIR_SPECIFIC_HEAT_J_KG_K;
    use irsig::thermal::{Exchange, Forcing, SolveOptions};
    let z_crt = us_crt_measurement_height_m();
    for d in [bondville_subset(), us_crt_subset()] {
        let us_crt = d.site() == FluxSite::UsCrt2011;
        let props = stock_props_with("crop", |s| {
            s.canopy = irsig::material::CanopyModel::TwoSource;
            if us_crt {
                s.measurement_height_m = Some(z_crt);
            }
        });
        let (history, _) = d.weather(0..d.len()).unwrap();
        let (sol, _) = solve_free_facet(
            &props,
            history.records(),
            &d.site().site(),
            &FacetSpec::default(),
            &SolveOptions::default(),
        )
        .unwrap();
        let forcing = Forcing::from_records(history.records()).unwrap();
        let ex = Exchange::new(&props, &forcing).unwrap();
        let mut acc = vec![[0.0f64; 20]; 24];
        for i in d.second_half() {
            let r = &d.records()[i];
            let w = &history.records()[i];
            let (Some(h), Some(le), Some(rn), Some(g), Some(tm)) = (
                r.sensible_heat_w_m2,
                r.latent_heat_w_m2,
                r.net_radiation_w_m2,
                r.ground_heat_w_m2,
                r.surface_temperature_k,
            ) else {
                continue;
            };
            if w.global_horizontal_w_m2 <= 20.0 {
                continue;
            }
            let step = &ex.two_source[i];
            let s = props.solar_absorptivity * w.global_horizontal_w_m2
                + props.thermal_emissivity * w.sky_longwave_w_m2;
            let t_s = sol.soil_temperature_k[i];
            let f = step.fluxes(s, t_s);
            assert!(
                f.canopy_residual_w_m2().abs() < 1e-6 * f.net_radiation_canopy_w_m2.abs().max(1.0),
                "{:?} record {i}: leaves' residual {}",
                d.site(),
                f.canopy_residual_w_m2()
            );
            let air = AirState::new(
                forcing.air_temperature_k[i],
                forcing.vapour_pressure_pa[i],
                forcing.pressure_pa[i],
            )
            .unwrap();
            let rho_cp = air.density_kg_m3() * AIR_SPECIFIC_HEAT_J_KG_K;
            let gamma = air.psychrometric_constant_pa_k();
            let [g_a, g_x, g_s, _, w_c, w_s] = step.conductances();
            let (r_x, r_soil) = (rho_cp / g_x, rho_cp / g_s);
            let bowen = if h + le != 0.0 {
                (rn - g) / (h + le)
            } else {
                1.0
            };
            let t_a = w.air_temperature_k;
            let v = [
                1.0,
                f.sensible_canopy_w_m2,
                f.sensible_soil_w_m2,
                f.latent_canopy_w_m2,
                f.latent_soil_w_m2,
                f.net_radiation_canopy_w_m2,
                f.net_radiation_soil_w_m2,
                f.ground_w_m2,
                h * bowen,
                le * bowen,
                rn,
                g,
                f.canopy_k - t_a,
                t_s - t_a,
                tm - t_a,
                rho_cp / g_a,
                r_x,
                (rho_cp / (gamma * w_c) - r_x).min(5000.0),
                r_soil,
                (rho_cp / (gamma * w_s) - r_soil).min(1e4),
            ];
            let hour = chrono::Timelike::hour(&w.time) as usize;
            for (a, x) in acc[hour].iter_mut().zip(v) {
                *a += x;
            }
        }
        println!(
            "{:?}, stock crop as two sources, daytime by local standard hour (W/m², K, s/m):\n\
             hour    n   H_c   H_s  LE_c  LE_s  Rn_c  Rn_s     G | H_cl LE_cl   Rn    G | \
             dT_c  dT_s dT_meas |  r_a   r_x  r_st r_soil  r_ss",
            d.site()
        );
        let mut all = [0.0; 20];
        let row = |label: String, a: &[f64; 20]| {
            let m: Vec<String> = a[1..].iter().map(|x| format!("{:5.0}", x / a[0])).collect();
            let t: Vec<String> = a[12..15]
                .iter()
                .map(|x| format!("{:+5.1}", x / a[0]))
                .collect();
            println!(
                "{label:>4} {:4} {} | {} | {} | {}",
                a[0],
                m[..7].join(" "),
                m[7..11].join(" "),
                t.join(" "),
                m[14..].join(" ")
            );
        };
        for (hour, a) in acc.iter().enumerate() {
            if a[0] > 0.0 {
                row(format!("{hour}"), a);
                for (s, x) in all.iter_mut().zip(a) {
                    *s += x;
                }
            }
        }
        row("all".into(), &all);
        if us_crt {
            assert!(all[1] > 3.0 * all[2], "H_c {} H_s {}", all[1], all[2]);
        }
    }
}

/// The first half's mean of US-CRT's column `col` (records with a value).
fn us_crt_first_half_mean(col: &str) -> f64 {
    let path = util::shared_data("flux").join("us-crt_2011/us-crt_2011_jul06-aug16.csv");
    let mut r = csv::Reader::from_path(path).unwrap();
    let i = r.headers().unwrap().iter().position(|h| h == col).unwrap();
    let v: Vec<f64> = r
        .records()
        .take(us_crt_subset().first_half().len())
        .filter_map(|row| row.unwrap().get(i)?.parse::<f64>().ok())
        .collect();
    v.iter().sum::<f64>() / v.len() as f64
}

/// The stock crop with its `surface_energy` block changed by `edit` and,
/// where given, its solar absorptivity.
fn crop_with(
    edit: &(dyn Fn(&mut irsig::material::SurfaceEnergySpec) + Sync),
    solar_absorptivity: Option<f64>,
) -> irsig::thermal::SlabProperties {
    let db = irsig::material::stock::stock().unwrap();
    let mut m = db.get("crop").unwrap().clone();
    edit(m.surface_energy.as_mut().unwrap());
    if let Some(a) = solar_absorptivity {
        m.solar_absorptivity = a;
    }
    irsig::thermal::SlabProperties::from_material(&m).unwrap()
}

/// Fit the crop `base` on the first half of `d` (Levenberg–Marquardt,
/// `irsig::analysis::calibrate`): Bondville its leaf area index, US-CRT
/// (growing to its README's heights) its leaf area per height; both the
/// minimum stomatal resistance, the starting soil water and the solar
/// absorptivity. Returns the fitted material and the fitted values.
fn calibrate_first_half(
    d: &FluxDataset,
    base: &(dyn Fn(&mut irsig::material::SurfaceEnergySpec) + Sync),
) -> (irsig::thermal::SlabProperties, Vec<(String, f64)>) {
    use irsig::analysis::calibrate::{CalibrationOptions, calibrate};
    use irsig::analysis::facet::{FacetSpec, solve_free_facet};
    use irsig::analysis::sensitivity::Factor;
    let us_crt = d.site() == FluxSite::UsCrt2011;
    let first = d.first_half();
    let (history, _) = d.weather(first.clone()).unwrap();
    let site = d.site().site();
    let idx: Vec<usize> = first
        .clone()
        .filter(|&i| d.records()[i].surface_temperature_k.is_some())
        .collect();
    let truth: Vec<f64> = idx
        .iter()
        .map(|&i| d.records()[i].surface_temperature_k.unwrap())
        .collect();
    let sat = crop_with(base, None).surface.unwrap();
    let theta_max = sat.root_zone.map_or(0.32, |z| z.saturation_m3_m3.min(0.5));
    let factor = |name: &str, nominal: f64, low: f64, high: f64| Factor {
        name: name.into(),
        nominal,
        low,
        high,
        uncertainty: 0.0,
    };
    let spec = |x: &[f64]| {
        let x = x.to_vec();
        move |s: &mut irsig::material::SurfaceEnergySpec| {
            base(s);
            if us_crt {
                s.leaf_area_per_height_per_m = Some(x[0]);
            } else {
                s.leaf_area_index = x[0];
            }
            s.min_stomatal_resistance_s_m = x[1];
            s.soil_moisture_m3_m3 = x[2];
        }
    };
    let factors = vec![
        if us_crt {
            factor("leaf_area_per_height_per_m", 6.8, 1.0, 30.0)
        } else {
            factor("leaf_area_index", 3.0, 0.5, 7.0)
        },
        factor("min_stomatal_resistance_s_m", 180.0, 30.0, 400.0),
        factor(
            "soil_moisture_m3_m3",
            0.28_f64.min(theta_max),
            0.13,
            theta_max,
        ),
        factor("solar_absorptivity", 0.8, 0.7, 0.9),
    ];
    let model = |x: &[f64]| -> irsig::error::Result<Vec<f64>> {
        let props = crop_with(&spec(x), Some(x[3]));
        let (sol, _) = solve_free_facet(
            &props,
            history.records(),
            &site,
            &FacetSpec::default(),
            &irsig::thermal::SolveOptions::default(),
        )?;
        Ok(idx
            .iter()
            .map(|&i| sol.surface_temperature_k[i - first.start])
            .collect())
    };
    let c = calibrate(&factors, &truth, &model, CalibrationOptions::default()).unwrap();
    let x: Vec<f64> = c.params.iter().map(|p| p.fitted).collect();
    (
        crop_with(&spec(&x), Some(x[3])),
        c.params
            .iter()
            .map(|p| (p.name.clone(), p.fitted))
            .collect(),
    )
}

/// The root-zone water budget under the two-source canopy, and water from a
/// water table, on both sites: the stock crop as two sources (θ constant;
/// the reference), with a 1 m root zone (FAO-56 Table 22: soybean
/// 0.6–1.3 m) from the stock θ 0.28, from the first measured θ (US-CRT:
/// its silty clay, Clapp & Hornberger's porosity 0.492), and at US-CRT over
/// its water table at the first half's measured mean depth (README column
/// `water_table_depth_m`; Bondville's README and the literature found give
/// no depth: no such row there), in the silty clay; the big leaf over the
/// same table for comparison. Each uncalibrated, and the two-source rows
/// calibrated on the first half ([`calibrate_first_half`]); second half
/// scored. Printed for `docs/physics/validation.md`. Asserted: every
/// stock row beats T_air, θ stays in [0, θ_sat], the water budget of every
/// run closes to 1e-9 of its gross flux, and at US-CRT the water table
/// supplies water (capillary rise > 0) and keeps θ above the bucket's
/// without it.
#[test]
#[ignore = "needs ../shared/data"]
fn soil_water_two_source_on_measured_forcing() {
    use irsig::material::{CanopyModel, SoilTexture};
    let us_crt_z = us_crt_measurement_height_m();
    let table_m = -us_crt_first_half_mean("water_table_depth_m");
    println!("US-CRT first-half mean water-table depth {table_m:.3} m");
    for d in [bondville_subset(), us_crt_subset()] {
        let us_crt = d.site() == FluxSite::UsCrt2011;
        let theta0 = measured_soil_water(&d)[0].unwrap();
        let mut theta_end = std::collections::HashMap::new();
        for name in [
            "two_source",
            "two_source water",
            "two_source water measured",
            "two_source water measured table",
            "water measured table",
        ] {
            if name.contains("table") && !us_crt {
                continue;
            }
            let edit = move |s: &mut irsig::material::SurfaceEnergySpec| {
                if us_crt {
                    s.measurement_height_m = Some(us_crt_z);
                    s.phenology = us_crt_heights();
                    s.leaf_area_per_height_per_m = Some(6.8);
                }
                if name.contains("two_source") {
                    s.canopy = CanopyModel::TwoSource;
                }
                if name.contains("water") {
                    s.root_zone_depth_m = Some(1.0);
                }
                if name.contains("measured") {
                    s.soil_moisture_m3_m3 = theta0;
                    if us_crt {
                        s.soil_texture = Some(SoilTexture::SiltyClay);
                    }
                }
                if name.contains("table") {
                    s.water_table_depth_m = Some(table_m);
                }
            };
            let stock = crop_with(&edit, None);
            let mut runs = vec![("stock".to_string(), stock)];
            if name.starts_with("two_source") {
                let (fitted, x) = calibrate_first_half(&d, &edit);
                let x: Vec<String> = x.iter().map(|(n, v)| format!("{n} {v:.3}")).collect();
                runs.push((format!("calibrated ({})", x.join(", ")), fitted));
            }
            for (label, props) in runs {
                let r = props_on_site(&props, &d);
                let (le_m, _, h_m, _) = r.day_fluxes;
                let c = &r.day_closed;
                let hemi = r.rmse_hemispherical.map_or("—".into(), |(rmse, bias)| {
                    format!("{rmse:.2} K ({bias:+.2})")
                });
                println!(
                    "{:?}: crop {name}, {label}: RMSE {:.2} K (T_air {:.2}), bias {:+.2} K, \
                     Spearman {:.3}, hemispherical {hemi}; daytime H {h_m:.0} / closure-corrected \
                     {:.0}, LE {le_m:.0} / {:.0} W/m²",
                    d.site(),
                    r.rmse,
                    r.air_rmse,
                    r.bias,
                    r.spearman,
                    c.h_closed,
                    c.le_closed
                );
                if label == "stock" {
                    assert!(r.rmse < r.air_rmse, "{:?} {name}: {}", d.site(), r.rmse);
                }
                if r.soil_moisture.is_empty() {
                    continue;
                }
                let zone = props.surface.unwrap().root_zone.unwrap();
                let ex = irsig::thermal::Exchange::new(&props, &{
                    let (h, _) = d.weather(0..d.len()).unwrap();
                    irsig::thermal::Forcing::from_records(h.records()).unwrap()
                })
                .unwrap();
                let (mut net, mut gross, mut rise) = (0.0, 0.0, 0.0);
                for s in &ex.soil_water {
                    net += s.infiltration_mm - s.evaporation_mm + s.capillary_rise_mm
                        - s.drainage_mm
                        - s.runoff_mm;
                    gross += s.infiltration_mm
                        + s.evaporation_mm.abs()
                        + s.capillary_rise_mm
                        + s.drainage_mm
                        + s.runoff_mm;
                    rise += s.capillary_rise_mm;
                }
                let th = &ex.soil_moisture_m3_m3;
                let change = zone.storage_mm(th[th.len() - 1]) - zone.storage_mm(th[0]);
                assert!(
                    (change - net).abs() <= 1e-9 * gross,
                    "{name}: {change} vs {net}"
                );
                assert!(
                    th.iter()
                        .all(|&t| (0.0..=zone.saturation_m3_m3 + 1e-12).contains(&t))
                );
                let measured = measured_soil_water(&d);
                let (mut m, mut o) = (Vec::new(), Vec::new());
                for i in d.second_half() {
                    if let Some(t) = measured[i] {
                        m.push(th[i]);
                        o.push(t);
                    }
                }
                let first = d.second_half().start;
                println!(
                    "{:?}: crop {name}, {label}: θ second half {:.3} → {:.3} (measured {:.3} → \
                     {:.3}), RMSE {:.3} m³/m³; ET {:.0} mm, rain in {:.0}, drained {:.0}, \
                     capillary rise {rise:.0} mm over the 42 days",
                    d.site(),
                    th[first],
                    th[th.len() - 1],
                    o[0],
                    o[o.len() - 1],
                    stats::rmse(&m, &o).unwrap(),
                    ex.soil_water.iter().map(|s| s.evaporation_mm).sum::<f64>(),
                    ex.soil_water.iter().map(|s| s.infiltration_mm).sum::<f64>(),
                    ex.soil_water.iter().map(|s| s.drainage_mm).sum::<f64>(),
                );
                if label == "stock" {
                    theta_end.insert(
                        name,
                        th[first..].iter().sum::<f64>() / (th.len() - first) as f64,
                    );
                    if name.contains("table") {
                        assert!(rise > 0.0, "{name}: the table supplies water");
                    }
                }
            }
        }
        if us_crt {
            assert!(
                theta_end["two_source water measured table"]
                    > theta_end["two_source water measured"],
                "{theta_end:?}"
            );
        }
    }
}

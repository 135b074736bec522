//! The six AFGL model atmospheres: temperature, pressure, water vapour and
//! ozone from the ground to 50 km.
//!
//! Source: G. P. Anderson, S. A. Clough, F. X. Kneizys, J. H. Chetwynd and
//! E. P. Shettle, *AFGL Atmospheric Constituent Profiles (0–120 km)*,
//! AFGL-TR-86-0110 (Air Force Geophysics Laboratory, 1986), tables 1a–1f —
//! the model atmospheres of LOWTRAN 7 and MODTRAN (a US Government work,
//! public domain). Levels every 1 km to 25 km, then every 2.5 km to 50 km;
//! pressure in mb, temperature in K, H₂O and O₃ volume mixing ratios in
//! ppmv, as tabulated.
//!
//! Between levels temperature and ozone are linear in altitude, pressure and
//! water vapour log-linear (exponential between levels, as the hydrostatic
//! equation makes them); above 50 km the top level holds, below 0 km the
//! lowest.
//!
//! [`Profile::for_site`] picks a profile by latitude and month where a scene
//! names none: |latitude| < 20° tropical, 20–55° mid-latitude, ≥ 55°
//! sub-arctic; summer from April to September in the northern hemisphere
//! (October to March in the southern). This is the usual convention for
//! choosing among the LOWTRAN/MODTRAN model atmospheres (e.g. the FLAASH
//! user guide's latitude-by-month table), simplified to three bands.
//!
//! Owns the tables and their interpolation. Takes an altitude; gives the
//! air's state. Must not know spectra, paths or weather records.

use crate::{Error, Result};

/// One tabulated level: altitude km, pressure mb, temperature K, H₂O ppmv,
/// O₃ ppmv.
type Level = [f64; 5];
const ROWS: usize = 36;

/// An AFGL model atmosphere (Anderson et al. 1986).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Profile {
    /// Tropical (15° N, annual mean).
    Tropical,
    /// Mid-latitude summer (45° N, July).
    MidLatitudeSummer,
    /// Mid-latitude winter (45° N, January).
    MidLatitudeWinter,
    /// Sub-arctic summer (60° N, July).
    SubArcticSummer,
    /// Sub-arctic winter (60° N, January).
    SubArcticWinter,
    /// US Standard Atmosphere 1976.
    UsStandard,
}

/// The air of a profile at one altitude.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ProfileLevel {
    /// Temperature, K.
    pub temperature_k: f64,
    /// Pressure, Pa.
    pub pressure_pa: f64,
    /// Water-vapour volume mixing ratio, ppmv.
    pub h2o_ppmv: f64,
    /// Ozone volume mixing ratio, ppmv.
    pub o3_ppmv: f64,
}

impl Profile {
    /// Every profile, in the order of the AFGL report.
    pub const ALL: [Profile; 6] = [
        Profile::Tropical,
        Profile::MidLatitudeSummer,
        Profile::MidLatitudeWinter,
        Profile::SubArcticSummer,
        Profile::SubArcticWinter,
        Profile::UsStandard,
    ];

    /// The profile's name in scene files and on the command line.
    pub fn name(self) -> &'static str {
        match self {
            Profile::Tropical => "tropical",
            Profile::MidLatitudeSummer => "mid-latitude-summer",
            Profile::MidLatitudeWinter => "mid-latitude-winter",
            Profile::SubArcticSummer => "sub-arctic-summer",
            Profile::SubArcticWinter => "sub-arctic-winter",
            Profile::UsStandard => "us-standard",
        }
    }

    /// The profile named `name` (see [`Profile::name`]); an error listing
    /// the valid names otherwise.
    pub fn from_name(name: &str) -> Result<Profile> {
        Profile::ALL
            .into_iter()
            .find(|p| p.name() == name)
            .ok_or_else(|| {
                let valid: Vec<&str> = Profile::ALL.iter().map(|p| p.name()).collect();
                Error::invalid(
                    "profile",
                    format!(
                        "unknown profile `{name}`: expected one of {}{}",
                        valid.join(", "),
                        crate::suggest::hint(name, valid.iter().copied())
                    ),
                )
            })
    }

    /// The profile for a site at `latitude_deg` in `month` (1–12), by the
    /// convention of the module docs.
    pub fn for_site(latitude_deg: f64, month: u32) -> Profile {
        let lat = latitude_deg.abs();
        let northern_summer = (4..=9).contains(&month);
        let summer = if latitude_deg >= 0.0 {
            northern_summer
        } else {
            !northern_summer
        };
        match (lat < 20.0, lat < 55.0, summer) {
            (true, _, _) => Profile::Tropical,
            (false, true, true) => Profile::MidLatitudeSummer,
            (false, true, false) => Profile::MidLatitudeWinter,
            (false, false, true) => Profile::SubArcticSummer,
            (false, false, false) => Profile::SubArcticWinter,
        }
    }

    fn table(self) -> &'static [Level; ROWS] {
        match self {
            Profile::Tropical => &TROPICAL,
            Profile::MidLatitudeSummer => &MID_LATITUDE_SUMMER,
            Profile::MidLatitudeWinter => &MID_LATITUDE_WINTER,
            Profile::SubArcticSummer => &SUB_ARCTIC_SUMMER,
            Profile::SubArcticWinter => &SUB_ARCTIC_WINTER,
            Profile::UsStandard => &US_STANDARD,
        }
    }

    /// The air at altitude `z_m` (m above sea level), interpolated as the
    /// module docs say.
    pub fn level(self, z_m: f64) -> ProfileLevel {
        let t = self.table();
        let z = (z_m / 1000.0).clamp(t[0][0], t[ROWS - 1][0]);
        let i = t.partition_point(|r| r[0] <= z).clamp(1, ROWS - 1);
        let (a, b) = (&t[i - 1], &t[i]);
        let f = ((z - a[0]) / (b[0] - a[0])).clamp(0.0, 1.0);
        let lin = |k: usize| a[k] + f * (b[k] - a[k]);
        let log = |k: usize| (a[k].ln() + f * (b[k].ln() - a[k].ln())).exp();
        ProfileLevel {
            temperature_k: lin(2),
            pressure_pa: log(1) * 100.0,
            h2o_ppmv: log(3),
            o3_ppmv: lin(4),
        }
    }
}

impl std::fmt::Display for Profile {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// Tropical (15° N, annual mean); Anderson et al. table 1a.
pub(super) const TROPICAL: [Level; ROWS] = [
    [0.0, 1013.0, 299.7, 25900.0, 0.0287],
    [1.0, 904.0, 293.7, 19500.0, 0.0315],
    [2.0, 805.0, 287.7, 15300.0, 0.0334],
    [3.0, 715.0, 283.7, 8600.0, 0.035],
    [4.0, 633.0, 277.0, 4440.0, 0.0356],
    [5.0, 559.0, 270.3, 3350.0, 0.0377],
    [6.0, 492.0, 263.6, 2100.0, 0.0399],
    [7.0, 432.0, 257.0, 1290.0, 0.0422],
    [8.0, 378.0, 250.3, 764.0, 0.0447],
    [9.0, 329.0, 243.6, 410.0, 0.05],
    [10.0, 286.0, 237.0, 191.0, 0.0559],
    [11.0, 247.0, 230.1, 73.1, 0.0661],
    [12.0, 213.0, 223.6, 29.1, 0.0781],
    [13.0, 182.0, 217.0, 9.9, 0.0929],
    [14.0, 156.0, 210.3, 6.22, 0.105],
    [15.0, 132.0, 203.7, 4.0, 0.126],
    [16.0, 111.0, 197.0, 3.0, 0.144],
    [17.0, 93.7, 194.8, 2.9, 0.25],
    [18.0, 78.9, 198.8, 2.75, 0.5],
    [19.0, 66.6, 202.7, 2.6, 0.95],
    [20.0, 56.5, 206.7, 2.6, 1.4],
    [21.0, 48.0, 210.7, 2.65, 1.8],
    [22.0, 40.9, 214.6, 2.8, 2.4],
    [23.0, 35.0, 217.0, 2.9, 3.4],
    [24.0, 30.0, 219.2, 3.2, 4.3],
    [25.0, 25.7, 221.4, 3.25, 5.4],
    [27.5, 17.63, 227.0, 3.6, 7.8],
    [30.0, 12.2, 232.3, 4.0, 9.3],
    [32.5, 8.52, 237.7, 4.3, 9.85],
    [35.0, 6.0, 243.1, 4.6, 9.7],
    [37.5, 4.26, 248.5, 4.9, 8.8],
    [40.0, 3.05, 254.0, 5.2, 7.5],
    [42.5, 2.2, 259.4, 5.5, 5.9],
    [45.0, 1.59, 264.8, 5.7, 4.5],
    [47.5, 1.16, 269.6, 5.9, 3.45],
    [50.0, 0.854, 270.2, 6.0, 2.8],
];

/// Mid-latitude summer (45° N, July); table 1b.
pub(super) const MID_LATITUDE_SUMMER: [Level; ROWS] = [
    [0.0, 1013.0, 294.2, 18800.0, 0.0302],
    [1.0, 902.0, 289.7, 13800.0, 0.0334],
    [2.0, 802.0, 285.2, 9680.0, 0.0369],
    [3.0, 710.0, 279.2, 5980.0, 0.0422],
    [4.0, 628.0, 273.2, 3810.0, 0.0482],
    [5.0, 554.0, 267.2, 2230.0, 0.0551],
    [6.0, 487.0, 261.2, 1510.0, 0.0641],
    [7.0, 426.0, 254.7, 1020.0, 0.0776],
    [8.0, 372.0, 248.2, 646.0, 0.0913],
    [9.0, 324.0, 241.7, 413.0, 0.111],
    [10.0, 281.0, 235.3, 247.0, 0.13],
    [11.0, 243.0, 228.8, 95.6, 0.179],
    [12.0, 209.0, 222.3, 29.4, 0.223],
    [13.0, 179.0, 215.8, 8.0, 0.3],
    [14.0, 153.0, 215.7, 5.0, 0.44],
    [15.0, 130.0, 215.7, 3.4, 0.5],
    [16.0, 111.0, 215.7, 3.3, 0.6],
    [17.0, 95.0, 215.7, 3.2, 0.7],
    [18.0, 81.2, 216.8, 3.15, 1.0],
    [19.0, 69.5, 217.9, 3.2, 1.5],
    [20.0, 59.5, 219.2, 3.3, 2.0],
    [21.0, 51.0, 220.4, 3.45, 2.4],
    [22.0, 43.7, 221.6, 3.6, 2.9],
    [23.0, 37.6, 222.8, 3.85, 3.4],
    [24.0, 32.2, 223.9, 4.0, 4.0],
    [25.0, 27.7, 225.1, 4.2, 4.8],
    [27.5, 19.1, 228.5, 4.45, 6.0],
    [30.0, 13.2, 233.7, 4.7, 7.0],
    [32.5, 9.3, 239.0, 4.85, 8.1],
    [35.0, 6.52, 245.2, 4.95, 8.9],
    [37.5, 4.64, 251.3, 5.0, 8.7],
    [40.0, 3.33, 257.5, 5.1, 7.55],
    [42.5, 2.41, 263.7, 5.3, 5.9],
    [45.0, 1.76, 269.9, 5.45, 4.5],
    [47.5, 1.29, 275.2, 5.5, 3.5],
    [50.0, 0.951, 275.7, 5.5, 2.8],
];

/// Mid-latitude winter (45° N, January); table 1c.
pub(super) const MID_LATITUDE_WINTER: [Level; ROWS] = [
    [0.0, 1018.0, 272.2, 4320.0, 0.0278],
    [1.0, 897.3, 268.7, 3450.0, 0.028],
    [2.0, 789.7, 265.2, 2790.0, 0.0285],
    [3.0, 693.8, 261.7, 2090.0, 0.032],
    [4.0, 608.1, 255.7, 1280.0, 0.0357],
    [5.0, 531.3, 249.7, 824.0, 0.0472],
    [6.0, 462.7, 243.7, 510.0, 0.0584],
    [7.0, 401.6, 237.7, 232.0, 0.0789],
    [8.0, 347.3, 231.7, 108.0, 0.104],
    [9.0, 299.3, 225.7, 55.7, 0.157],
    [10.0, 256.8, 219.7, 29.6, 0.237],
    [11.0, 219.9, 219.2, 10.0, 0.362],
    [12.0, 188.2, 218.7, 6.0, 0.523],
    [13.0, 161.1, 218.2, 5.0, 0.704],
    [14.0, 137.8, 217.7, 4.8, 0.8],
    [15.0, 117.8, 217.2, 4.7, 0.9],
    [16.0, 100.7, 216.7, 4.6, 1.1],
    [17.0, 86.1, 216.2, 4.5, 1.4],
    [18.0, 73.6, 215.7, 4.5, 1.8],
    [19.0, 62.8, 215.2, 4.5, 2.3],
    [20.0, 53.7, 215.2, 4.5, 2.9],
    [21.0, 45.8, 215.2, 4.5, 3.5],
    [22.0, 39.1, 215.2, 4.53, 3.9],
    [23.0, 33.4, 215.2, 4.55, 4.3],
    [24.0, 28.6, 215.2, 4.6, 4.7],
    [25.0, 24.4, 215.2, 4.65, 5.1],
    [27.5, 16.46, 215.5, 4.7, 5.6],
    [30.0, 11.1, 217.4, 4.75, 6.1],
    [32.5, 7.56, 220.4, 4.8, 6.8],
    [35.0, 5.18, 227.9, 4.85, 7.1],
    [37.5, 3.6, 235.5, 4.9, 7.2],
    [40.0, 2.53, 243.2, 4.95, 6.9],
    [42.5, 1.8, 250.8, 5.0, 5.9],
    [45.0, 1.29, 258.5, 5.0, 4.6],
    [47.5, 0.94, 265.1, 5.0, 3.7],
    [50.0, 0.683, 265.7, 4.95, 2.75],
];

/// Sub-arctic summer (60° N, July); table 1d.
pub(super) const SUB_ARCTIC_SUMMER: [Level; ROWS] = [
    [0.0, 1010.0, 287.2, 11900.0, 0.0241],
    [1.0, 896.0, 281.7, 8700.0, 0.0294],
    [2.0, 792.9, 276.3, 6750.0, 0.0338],
    [3.0, 700.0, 270.9, 4820.0, 0.0389],
    [4.0, 616.0, 265.5, 3380.0, 0.0448],
    [5.0, 541.0, 260.1, 2220.0, 0.0533],
    [6.0, 474.0, 253.1, 1330.0, 0.0656],
    [7.0, 413.0, 246.1, 797.0, 0.0774],
    [8.0, 359.0, 239.2, 400.0, 0.0911],
    [9.0, 310.8, 232.2, 130.0, 0.142],
    [10.0, 267.7, 225.2, 42.4, 0.189],
    [11.0, 230.0, 225.2, 13.3, 0.305],
    [12.0, 197.7, 225.2, 6.0, 0.41],
    [13.0, 170.0, 225.2, 4.45, 0.5],
    [14.0, 146.0, 225.2, 4.0, 0.6],
    [15.0, 126.0, 225.2, 4.0, 0.7],
    [16.0, 108.0, 225.2, 4.0, 0.85],
    [17.0, 92.8, 225.2, 4.05, 1.0],
    [18.0, 79.8, 225.2, 4.3, 1.3],
    [19.0, 68.6, 225.2, 4.5, 1.7],
    [20.0, 59.0, 225.2, 4.6, 2.1],
    [21.0, 50.7, 225.2, 4.7, 2.7],
    [22.0, 43.6, 225.2, 4.8, 3.3],
    [23.0, 37.5, 225.2, 4.83, 3.7],
    [24.0, 32.28, 226.6, 4.85, 4.2],
    [25.0, 27.8, 228.1, 4.9, 4.5],
    [27.5, 19.23, 231.1, 4.95, 5.3],
    [30.0, 13.4, 235.1, 5.0, 5.7],
    [32.5, 9.4, 240.0, 5.0, 6.9],
    [35.0, 6.61, 247.2, 5.0, 7.7],
    [37.5, 4.72, 254.6, 5.0, 7.8],
    [40.0, 3.4, 262.1, 5.0, 7.0],
    [42.5, 2.48, 269.5, 5.0, 5.4],
    [45.0, 1.82, 273.6, 5.0, 4.2],
    [47.5, 1.34, 276.2, 5.0, 3.2],
    [50.0, 0.987, 277.2, 4.95, 2.5],
];

/// Sub-arctic winter (60° N, January); table 1e.
pub(super) const SUB_ARCTIC_WINTER: [Level; ROWS] = [
    [0.0, 1013.0, 257.2, 1410.0, 0.018],
    [1.0, 887.8, 259.1, 1620.0, 0.0207],
    [2.0, 777.5, 255.9, 1430.0, 0.0234],
    [3.0, 679.8, 252.7, 1170.0, 0.0277],
    [4.0, 593.2, 247.7, 790.0, 0.0325],
    [5.0, 515.8, 240.9, 431.0, 0.038],
    [6.0, 446.7, 234.1, 237.0, 0.0445],
    [7.0, 385.3, 227.3, 147.0, 0.0725],
    [8.0, 330.8, 220.9, 33.8, 0.104],
    [9.0, 282.9, 217.2, 29.8, 0.21],
    [10.0, 241.8, 217.2, 20.0, 0.3],
    [11.0, 206.7, 217.2, 10.0, 0.35],
    [12.0, 176.6, 217.2, 6.0, 0.4],
    [13.0, 151.0, 217.2, 4.45, 0.65],
    [14.0, 129.1, 217.2, 4.5, 0.9],
    [15.0, 110.3, 217.2, 4.55, 1.2],
    [16.0, 94.31, 216.6, 4.6, 1.5],
    [17.0, 80.58, 216.0, 4.65, 1.9],
    [18.0, 68.82, 215.4, 4.7, 2.45],
    [19.0, 58.75, 214.8, 4.75, 3.1],
    [20.0, 50.14, 214.2, 4.8, 3.7],
    [21.0, 42.77, 213.6, 4.85, 4.0],
    [22.0, 36.47, 213.0, 4.9, 4.2],
    [23.0, 31.09, 212.4, 4.95, 4.5],
    [24.0, 26.49, 211.8, 5.0, 4.6],
    [25.0, 22.56, 211.2, 5.0, 4.7],
    [27.5, 15.13, 213.6, 5.0, 4.9],
    [30.0, 10.2, 216.0, 5.0, 5.4],
    [32.5, 6.91, 218.5, 5.0, 5.9],
    [35.0, 4.701, 222.3, 5.0, 6.2],
    [37.5, 3.23, 228.5, 5.0, 6.25],
    [40.0, 2.243, 234.7, 5.0, 5.9],
    [42.5, 1.57, 240.8, 5.0, 5.1],
    [45.0, 1.113, 247.0, 5.0, 4.1],
    [47.5, 0.79, 253.2, 5.0, 3.0],
    [50.0, 0.5719, 259.3, 4.95, 2.6],
];

/// US Standard Atmosphere 1976 (with AFGL water vapour and ozone); table 1f.
pub(super) const US_STANDARD: [Level; ROWS] = [
    [0.0, 1013.0, 288.2, 7750.0, 0.0266],
    [1.0, 898.8, 281.7, 6070.0, 0.0293],
    [2.0, 795.0, 275.2, 4630.0, 0.0324],
    [3.0, 701.2, 268.7, 3180.0, 0.0332],
    [4.0, 616.6, 262.2, 2160.0, 0.0339],
    [5.0, 540.5, 255.7, 1400.0, 0.0377],
    [6.0, 472.2, 249.2, 925.0, 0.0411],
    [7.0, 411.1, 242.7, 572.0, 0.0501],
    [8.0, 356.5, 236.2, 367.0, 0.0597],
    [9.0, 308.0, 229.7, 158.0, 0.0917],
    [10.0, 265.0, 223.3, 70.0, 0.131],
    [11.0, 227.0, 216.8, 36.1, 0.215],
    [12.0, 194.0, 216.7, 19.1, 0.31],
    [13.0, 165.8, 216.7, 10.9, 0.385],
    [14.0, 141.7, 216.7, 5.93, 0.503],
    [15.0, 121.1, 216.7, 5.0, 0.651],
    [16.0, 103.5, 216.7, 3.95, 0.87],
    [17.0, 88.5, 216.7, 3.85, 1.19],
    [18.0, 75.65, 216.7, 3.83, 1.59],
    [19.0, 64.67, 216.7, 3.85, 2.03],
    [20.0, 55.29, 216.7, 3.9, 2.58],
    [21.0, 47.29, 217.6, 3.98, 3.03],
    [22.0, 40.47, 218.6, 4.07, 3.65],
    [23.0, 34.67, 219.6, 4.2, 4.17],
    [24.0, 29.72, 220.6, 4.3, 4.63],
    [25.0, 25.49, 221.6, 4.43, 5.12],
    [27.5, 17.43, 224.0, 4.58, 5.8],
    [30.0, 11.97, 226.5, 4.73, 6.55],
    [32.5, 8.01, 230.0, 4.82, 7.37],
    [35.0, 5.746, 236.5, 4.9, 7.84],
    [37.5, 4.15, 242.9, 4.95, 7.8],
    [40.0, 2.871, 250.4, 5.03, 7.3],
    [42.5, 2.06, 257.3, 5.15, 6.2],
    [45.0, 1.491, 264.2, 5.23, 5.25],
    [47.5, 1.09, 270.6, 5.25, 4.1],
    [50.0, 0.7978, 270.7, 5.23, 3.1],
];

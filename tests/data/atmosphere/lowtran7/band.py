"""Band values of a LOWTRAN 7 zenith run (run.sh output): the mean transmittance over
wavelength and the integral of the path radiance over wavelength, W m⁻² sr⁻¹, with the
5 cm⁻¹ samples interpolated linearly in wavelength (8001 points per band)."""
import sys
import numpy as np

def band(path, lo_um, hi_um):
    d = np.loadtxt(path)
    lam = 1e4 / d[:, 0]
    o = np.argsort(lam)
    x = np.linspace(lo_um, hi_um, 8001)
    tau = np.interp(x, lam[o], d[o, 1]).mean()
    rad = np.trapezoid(np.interp(x, lam[o], d[o, 2] * 1e4), x)
    return tau, rad

if __name__ == "__main__":
    t, l = band(sys.argv[1], float(sys.argv[2]), float(sys.argv[3]))
    print(f"{t:.4f},{l:.4f}")

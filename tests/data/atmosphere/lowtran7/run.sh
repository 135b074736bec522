#!/bin/bash
# Zenith sky run of LOWTRAN 7 (radiance mode, ground to 100 km, 5 cm⁻¹ steps).
# Usage: run.sh LT7_BINARY MODEL IHAZE V1 V2 [ZENITH_DEG [VIS_KM]] > OUT   (MODEL 1–6: tropical, mid-latitude
# summer, mid-latitude winter, sub-arctic summer, sub-arctic winter, US Standard;
# IHAZE 0: no aerosol, 1: rural, 4: maritime, 5: urban; VIS_KM the visibility, 0 or absent:
# the aerosol's default, 23 km rural and maritime, 5 km urban). OUT: wavenumber cm⁻¹, total transmittance,
# path radiance W cm⁻² sr⁻¹ µm⁻¹ (LOWTRAN's SUMVV).
set -euo pipefail
bin=$(realpath "$1"); m=$2; h=$3; v1=$4; v2=$5; a=${6:-0}; vis=${7:-0}
d=$(mktemp -d); trap 'rm -rf "$d"' EXIT; cd "$d"; mkdir out; touch out/TAPE6 out/TAPE7 out/TAPE8
{
  # CARD 1: MODEL ITYPE=2 (slant path) IEMSCT=1 (radiance) IMULT=0, M1–M6 MDEF IM NOPRT = 0, TBOUND SALB = 0
  printf '%5d%5d%5d%5d%5d%5d%5d%5d%5d%5d%5d%5d%5d%8.3f%7.2f\n' "$m" 2 1 0 0 0 0 0 0 0 0 0 0 0 0
  # CARD 2: IHAZE, ISEASN=0 (the model's season), no volcanic/cloud/rain, VIS
  printf '%5d%5d%5d%5d%5d%5d%10.3f%10.3f%10.3f%10.3f%10.3f\n' "$h" 0 0 0 0 0 "$vis" 0 0 0 0
  # CARD 3: H1=0 km, H2=100 km, ANGLE (zenith angle at H1)
  printf "%10.3f%10.3f%10.3f%10.3f%10.3f%10.3f%5d\n" 0 100 "$a" 0 0 0 0
  # CARD 4: V1 V2 DV=5 cm⁻¹; CARD 5: IRPT=0
  printf '%10.1f%10.1f%10.1f\n' "$v1" "$v2" 5
  printf '%5d\n' 0
} > TAPE5
"$bin" > /dev/null
cat out.txt

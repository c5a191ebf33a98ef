// Albedo textures of the simulator's surfaces: a function of 2D surface coordinates (u, v) in
// metres. Built from layers so that a surface can carry distinctive non-periodic detail (value
// noise, blobs, strokes), periodic structure (window grids: W §1 names repeated façades as a cause
// of wrong matches), road paint, or nothing at all (uniform albedo).
#pragma once

#include <cstdint>

namespace scanreg {

// A periodic grid of windows inside a rectangle of the surface.
struct WindowGrid {
  bool enabled = false;
  double u_min = 0, u_max = 0, v_min = 0, v_max = 0;  // region holding windows, metres
  double spacing_u = 3.0, spacing_v = 3.2;            // period, metres
  double width = 1.2, height = 1.6;                   // window opening, metres
  double offset_u = 0.9, offset_v = 0.9;              // lower-left corner of the first window in its cell, metres
  double frame_width = 0.08;                          // metres; 0 = no frame
  float glass_albedo = 0.10f;                         // windows are darker than the wall
  float frame_albedo = 0.85f;
  float variation = 0.0f;  // per-window random albedo change (curtains, blinds); 0 = all identical
};

// Road surface layout for the ground (v = across the street, u = along it; road centre v = 0).
struct GroundMarkings {
  bool enabled = false;
  double road_half_width = 5.0;  // metres: asphalt for |v| below this
  double sidewalk_outer = 8.5;   // metres: paving up to |v| = this, gravel/grass beyond
  double crosswalk_u[2] = {1e9, 1e9};  // zebra crossings centred at these u (1e9 = none)
  float paint_albedo = 0.85f;
  float sidewalk_albedo = 0.45f;
  float verge_albedo = 0.30f;
};

struct SurfaceTexture {
  float base = 0.5f;  // mean albedo in [0, 1]
  // Multi-octave value noise: amplitude (albedo units), coarsest wavelength, octaves.
  float noise_amplitude = 0.0f;
  double noise_wavelength_m = 2.0;
  int noise_octaves = 3;
  // Random soft-edged elliptic blobs (stains, posters, patches): at most one per cell.
  float blob_contrast = 0.0f;  // max |albedo change|
  double blob_cell_m = 2.0;
  double blob_probability = 0.5;
  double blob_radius_m = 0.6;  // <= blob_cell_m
  // Random thin strokes (cracks, graffiti, cables): at most one per cell.
  float stroke_contrast = 0.0f;
  double stroke_cell_m = 2.0;
  double stroke_probability = 0.3;
  double stroke_width_m = 0.05;
  double stroke_length_m = 1.5;  // <= stroke_cell_m
  WindowGrid windows;
  GroundMarkings ground;
  // A black-and-white checkerboard target: four squares meeting at (0, 0), light where u v > 0,
  // for |u|, |v| below this half size (metres; 0: none). Its sharp edges are averaged over the
  // beam's Gaussian footprint, as a real scanner's intensity is, so an edge cell returns grey.
  double checker_half_m = 0.0;
  float checker_dark = 0.05f, checker_light = 0.9f;
  std::uint64_t seed = 0;

  // Albedo at surface coordinates (u, v), metres; clamped to [0.02, 0.98]. footprint_half_m: the
  // standard deviation of the beam's footprint there (used by sharp-edged patterns: checkerboards).
  float Albedo(double u, double v, double footprint_half_m = 0.0) const;

  static SurfaceTexture Uniform(float albedo) {
    SurfaceTexture t;
    t.base = albedo;
    return t;
  }
};

}  // namespace scanreg

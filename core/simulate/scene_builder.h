// The simulator's building blocks shared by the street and city scenes: façade, poster and noise
// textures and a building with its street façade (internal to core/simulate).
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <array>

#include "core/simulate/random.h"
#include "core/simulate/scene.h"

namespace scanreg::sim {

// Asphalt and paving without road markings: noise, and (unless plain) patches, stains and cracks.
inline SurfaceTexture Pavement(std::uint64_t seed, bool plain) {
  SurfaceTexture t;
  t.seed = seed;
  t.base = 0.22f;
  t.noise_amplitude = plain ? 0.01f : 0.06f;
  t.noise_wavelength_m = 3.0;
  t.noise_octaves = 4;
  if (!plain) {
    t.blob_contrast = 0.07f;  // patches, stains, manhole covers
    t.blob_cell_m = 3.0;
    t.blob_probability = 0.35;
    t.blob_radius_m = 1.2;
    t.stroke_contrast = 0.12f;  // cracks, tar seams
    t.stroke_cell_m = 2.5;
    t.stroke_probability = 0.4;
    t.stroke_width_m = 0.03;
    t.stroke_length_m = 2.2;
  }
  return t;
}

struct Builder {
  Scene& scene;
  Rng& rng;
  bool repeated;  // kRepeatedWindows: identical, plain façades

  std::uint64_t Seed() { return rng.Next(); }

  SurfaceTexture Facade(double width, double height, bool textured) {
    SurfaceTexture t;
    t.seed = Seed();
    t.base = static_cast<float>(rng.Uniform(0.35, 0.75));
    if (textured) {
      t.noise_amplitude = static_cast<float>(rng.Uniform(0.03, 0.07));
      t.noise_wavelength_m = rng.Uniform(1.0, 4.0);
      t.blob_contrast = static_cast<float>(rng.Uniform(0.06, 0.16));
      t.blob_cell_m = 2.5;
      t.blob_probability = 0.3;
      t.blob_radius_m = 0.9;
      t.stroke_contrast = static_cast<float>(rng.Uniform(0.08, 0.18));
      t.stroke_probability = 0.15;
      t.stroke_width_m = 0.04;
    }
    WindowGrid& w = t.windows;
    w.enabled = true;
    w.spacing_u = rng.Uniform(2.4, 3.6);
    w.spacing_v = rng.Uniform(3.0, 3.5);
    w.width = rng.Uniform(1.0, std::min(1.8, w.spacing_u - 0.6));
    w.height = rng.Uniform(1.3, 1.9);
    w.offset_u = 0.5 * (w.spacing_u - w.width);
    w.offset_v = 0.9;
    w.u_min = 0.8;
    w.u_max = width - 0.8;
    w.v_min = rng.Uniform(3.6, 4.6);  // ground floor without the grid
    w.v_max = height - 0.8;
    w.glass_albedo = static_cast<float>(rng.Uniform(0.06, 0.16));
    w.frame_albedo = static_cast<float>(std::min(0.95, t.base + rng.Uniform(0.1, 0.3)));
    w.frame_width = rng.Uniform(0.05, 0.12);
    w.variation = textured ? 0.08f : 0.0f;
    return t;
  }

  // Posters, signs, graffiti: dense high-contrast blobs and strokes.
  SurfaceTexture Poster(float base) {
    SurfaceTexture t;
    t.seed = Seed();
    t.base = base;
    t.noise_amplitude = 0.05f;
    t.noise_wavelength_m = 0.8;
    t.blob_contrast = 0.3f;
    t.blob_cell_m = 0.5;
    t.blob_probability = 0.6;
    t.blob_radius_m = 0.25;
    t.stroke_contrast = 0.25f;
    t.stroke_cell_m = 0.4;
    t.stroke_probability = 0.5;
    t.stroke_width_m = 0.02;
    t.stroke_length_m = 0.35;
    return t;
  }

  SurfaceTexture Noisy(float base, float amplitude, double wavelength) {
    SurfaceTexture t;
    t.seed = Seed();
    t.base = base;
    t.noise_amplitude = amplitude;
    t.noise_wavelength_m = wavelength;
    return t;
  }

  // A building whose street façade is face `facade` (box frame) of an axis-aligned box.
  void Building(const Eigen::Vector3d& center, const Eigen::Vector3d& half, int facade, double facade_width, bool textured) {
    const int front = scene.AddTexture(Facade(facade_width, 2.0 * half.z(), textured));
    const int side = scene.AddTexture(SurfaceTexture::Uniform(static_cast<float>(rng.Uniform(0.3, 0.7))));
    std::array<int, 6> faces;
    faces.fill(side);
    faces[facade] = front;
    scene.AddBox(center, half, 0.0, faces);
  }
};

}  // namespace scanreg::sim

namespace scanreg {
// Adds the city of a kCity scene (ground, blocks, furniture) to `scene` (scene_city.cc).
void AddCity(const SceneOptions& options, Scene& scene, sim::Rng& rng);
// Adds the office floor of a kOffice or kOfficeIdentical scene (scene_office.cc).
void AddOffice(const SceneOptions& options, Scene& scene, sim::Rng& rng);
// Office floors: the x of the centre of the door nearest to x on the side y > 0 (side +1) or y < 0
// (-1), and |y| of the corridor walls' room face.
double OfficeDoorCentre(const SceneOptions& options, double x, double side);
double OfficeRoomFace();
inline bool IsOffice(SceneOptions::Kind kind) {
  return kind == SceneOptions::Kind::kOffice || kind == SceneOptions::Kind::kOfficeIdentical;
}
}  // namespace scanreg

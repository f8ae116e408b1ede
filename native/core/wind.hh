#pragma once
/* The wind, one model for every method: a field of air velocity, a uniform mean plus smooth
 * turbulence that travels with it (deterministic for a seed). Strands feel it through air
 * drag (Kurihara 1993, eq. 6, f = c_air (v_wind − v)); LCP through its air particles
 * (Bando 2003 §4.3) sampling the same field. */
#include <cstdint>

#include "core/math.hh"
#include "core/params.hh"

namespace hairdyn {

struct WindParams {
  /* m/s, the mean wind's speed. */
  float speed = 0.0f;
  /* World direction the wind blows toward (normalised; the zero vector means no wind).
   * Default: toward +Y, from the front of a Blender face. */
  vec3 direction = vec3(0.0f, 1.0f, 0.0f);
  /* Amplitude of the turbulence relative to the speed (0 = steady). */
  float turbulence = 0.3f;
  /* Hz, frequency of the turbulence. */
  float frequency = 0.5f;
  /* Seed of the turbulence: equal seeds give equal wind. */
  int32_t seed = 0;

  template<typename Fn> static void for_each_field(Fn &&fn)
  {
    fn(&WindParams::speed,
       ParamInfo{"speed", "|f|", "m/s", 0.0, 100.0,
                 "Speed of the mean wind (Kurihara 1993, eq. 6; Bando 2003, section 4.3)"}
           .soft(0.0, 20.0));
    fn(&WindParams::direction,
       ParamInfo{"direction", "", "", -1.0, 1.0,
                 "World direction the wind blows toward (normalised; zero means no wind)"});
    fn(&WindParams::turbulence,
       ParamInfo{"turbulence", "", "", 0.0, 10.0,
                 "Amplitude of the smooth turbulence relative to the wind's speed"}
           .soft(0.0, 1.0));
    fn(&WindParams::frequency,
       ParamInfo{"frequency", "", "Hz", 0.0, 100.0, "Frequency of the wind's turbulence"}
           .soft(0.0, 5.0));
    fn(&WindParams::seed,
       ParamInfo{"seed", "", "", 0.0, 2147483647.0, "Seed of the turbulence"});
  }
};

class WindField {
 public:
  WindField() = default;
  explicit WindField(const WindParams &params);
  /* m/s, the air's velocity at world point p and time t. */
  vec3 velocity_at(const vec3 &p, float time) const;
  /* True when the air is still everywhere. */
  bool is_calm() const { return mean_ == vec3(0.0f) && turbulence_ == 0.0f; }

 private:
  static constexpr int waves_num = 2; /* Sine waves per component of the turbulence. */
  vec3 mean_ = vec3(0.0f);
  float turbulence_ = 0.0f; /* m/s, amplitude of each component. */
  vec3 wave_vectors_[3][waves_num] = {};
  float angular_frequencies_[3][waves_num] = {};
  float phases_[3][waves_num] = {};
};

}  // namespace hairdyn

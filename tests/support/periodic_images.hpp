#pragma once
// Periodic test scenes placed for a box: some inclusions overlap an image of one of another
// phase, or span more periods than images are made for. The oracle refuses those, naming
// one; dropping them one at a time as named is what a user would do.
#include <cstddef>
#include <string>

#include "core/error.hpp"
#include "geometry/scene.hpp"

namespace cisamr::testing {

// `probe(scene)` builds the oracle (so this header needs no geometry library); at most
// `attempts` inclusions are dropped. Any other refusal is rethrown.
template <class Probe>
void drop_refused_images(geometry::SceneDesc& s, Probe&& probe, int attempts) {
  for (int attempt = 0; attempt < attempts && !s.inclusions.empty(); ++attempt) {
    try {
      probe(s);
      return;
    } catch (const InputError& e) {
      if (e.problem().find("periodic image") == std::string::npos && e.problem().find("periods") == std::string::npos)
        throw;
      const std::string& field = e.field();
      const std::size_t k = std::stoul(field.substr(field.find('[') + 1));
      s.inclusions.erase(s.inclusions.begin() + static_cast<std::ptrdiff_t>(k));
    }
  }
}

}  // namespace cisamr::testing

// Where a proxy is (its state and the mesh feature that holds it): what the
// proxy walks and what force shading reads, in a header of its own so that
// force shading needs no Proxy.
#pragma once

#include <cstdint>

#include "hapticut/tet_mesh.h"  // kNoTet.
#include "hapticut/vec3.h"

namespace hapticut {

enum class ProxyState : std::uint8_t { Tet = 0, Face = 1, Edge = 2, Vertex = 3, Outside = 4 };
inline constexpr int kProxyStateCount = 5;
const char* proxy_state_name(ProxyState state);

// Where the proxy is: its state, the tet that owns the state (docs/method.md,
// "Every constrained state is owned by a tet") and which of that tet's faces
// (0-3), edges (0-5) or vertices (0-3) constrains it.
struct ProxyPlace {
  ProxyState state = ProxyState::Outside;
  std::int32_t tet = kNoTet;
  std::int8_t local = 0;
  Vec3 q;
};

}  // namespace hapticut

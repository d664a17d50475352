#include "sflsh/sim/soft_tissue_terms.hpp"

#include <cmath>

#include "sflsh/core/error.hpp"
#include "sflsh/sim/energies/damping.hpp"
#include "sflsh/sim/energies/elastic.hpp"
#include "sflsh/sim/energies/gravity.hpp"
#include "sflsh/sim/energies/inertia.hpp"

namespace sflsh {

void add_soft_tissue_terms(ModelBuilder& builder, int body, const SoftTissueOptions& o) {
  require(o.damping >= 0 && std::isfinite(o.damping), "soft tissue damping = ", o.damping, " s, expected >= 0");
  const Avatar& a = builder.avatar(body);
  builder.add_term(std::make_unique<InertiaTerm>(a), body);
  auto elastic = std::make_shared<const ElasticTerm>(a, true, true, o.mean_dilatation);
  builder.add_term(elastic, {body});
  if (o.gravity && builder.options().gravity.squaredNorm() > 0) builder.add_term(std::make_unique<GravityTerm>(a), body);
  if (o.damping > 0) builder.add_term(std::make_unique<DampingTerm>(a, *elastic, o.damping), body);
}

}  // namespace sflsh

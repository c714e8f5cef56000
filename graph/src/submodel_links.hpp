#pragma once
// What a submodel needs from the rest once its own (and borrowed) bodies are chosen.
#include "body_csr.hpp"
#include "mbsflow/graph/decomposition.hpp"

namespace mbsflow {

// Per body, the joints and force elements that reach it (ground joints included).
struct BodyLinks {
  explicit BodyLinks(const Model& m);
  BodyCsr joints, elements;
};

// Fills each submodel's joints, ghosts, cut_joints and exchanges from its own and borrowed
// bodies and d.part_of_body (each body's owner).
void link_submodels(const Model& m, Decomposition& d);

}  // namespace mbsflow

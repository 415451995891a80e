// The techniques `pseudohaptic study` runs (docs/STUDY.md, "Techniques"): every method of the registry
// (core/engine/methods.hpp) with its default parameters, a method with a delta_beta_sign parameter once per
// reading of the sign, and the interrogation effects (materials, isophote wells) layered on the curvature
// method. A method added to the registry is run without a change here.
#pragma once

#include <string>
#include <vector>

#include "core/lab/study.hpp"

namespace ph::tools {

std::vector<StudyTechnique> study_techniques();

// The two techniques the paper compared, as this engine names them: the curvature method with Eq. 1's printed
// sign and the depth method.
inline constexpr const char* kPaperCurvature = "curvature:sign+1";
inline constexpr const char* kPaperDepth = "depth";

// The paper's method a technique stands for ("curvature", "depth"), or "" for one it did not run.
std::string paper_method_of(const std::string& technique);

}  // namespace ph::tools

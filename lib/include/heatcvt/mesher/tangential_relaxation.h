#pragma once
/// \file tangential_relaxation.h
/// Tangential relaxation: every vertex towards the area-weighted centroid of its one-ring, in its
/// tangent plane, projected back to the surface.
#include "heatcvt/mesher/projector.h"
#include "heatcvt/mesher/working_mesh.h"

namespace heatcvt {

/// One step of tangential relaxation (Jacobi: every vertex computed from the old positions, in
/// parallel). A vertex's move is kept only if none of its triangles then faces against its new
/// normal. `threads`: 0 = all cores; the result does not depend on it.
void tangential_relaxation(WorkingMesh& mesh, const SurfaceProjector& surface, int threads = 0);

}  // namespace heatcvt

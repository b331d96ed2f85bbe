#pragma once
/// \file compaction.h
/// The final mesh of the working mesh: unused vertices dropped.
#include "heatcvt/mesh.h"
#include "heatcvt/mesher/working_mesh.h"

namespace heatcvt {

/// The mesh's faces on the vertices they use, in increasing vertex index (faces keep their
/// order). `unused` receives the number of vertices dropped.
TriangleMesh compact_mesh(const WorkingMesh& mesh, int* unused = nullptr);

}  // namespace heatcvt

#pragma once
/// \file compaction.h
/// The final mesh of the working mesh (unused vertices dropped), and the converse: a finished
/// mesh taken back as a working mesh for a stage that edits it.
#include "heatcvt/mesh.h"
#include "heatcvt/mesher/projector.h"
#include "heatcvt/mesher/working_mesh.h"

namespace heatcvt {

/// The mesh's faces on the vertices they use, in increasing vertex index (faces keep their
/// order). `unused` receives the number of vertices dropped.
TriangleMesh compact_mesh(const WorkingMesh& mesh, int* unused = nullptr);

/// `mesh` as a working mesh: the same positions and faces (in order), each vertex's normal and
/// anchor those of its projection onto `surface`.
WorkingMesh working_mesh_of(const TriangleMesh& mesh, const SurfaceProjector& surface);

}  // namespace heatcvt

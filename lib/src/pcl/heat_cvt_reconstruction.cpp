// Explicit instantiations of heatcvt::HeatCVTReconstruction for the common PCL point types.
#include <pcl/point_types.h>

#include "heatcvt/pcl/heat_cvt_reconstruction.h"
#include "heatcvt/pcl/impl/heat_cvt_reconstruction.hpp"

template class heatcvt::HeatCVTReconstruction<pcl::PointXYZ>;
template class heatcvt::HeatCVTReconstruction<pcl::PointNormal>;
template class heatcvt::HeatCVTReconstruction<pcl::PointXYZRGBNormal>;

// Explicit instantiations of heatcvt::HeatVoronoiSegmentation for the common PCL point types.
#include <pcl/point_types.h>

#include "heatcvt/pcl/heat_voronoi_segmentation.h"
#include "heatcvt/pcl/impl/heat_voronoi_segmentation.hpp"

template class heatcvt::HeatVoronoiSegmentation<pcl::PointXYZ>;
template class heatcvt::HeatVoronoiSegmentation<pcl::PointNormal>;
template class heatcvt::HeatVoronoiSegmentation<pcl::PointXYZRGBNormal>;

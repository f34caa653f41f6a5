#version 430 core
// The dispatch arguments of trace_hiz_list.comp from the length of the list
// (hiz_rays.glsl): a row of at most 65535 groups (the least
// GL_MAX_COMPUTE_WORK_GROUP_COUNT GL allows), as many rows as that takes.
#include "hiz_rays.glsl"

layout(local_size_x = 1) in;

void main() {
  uint groups = (count + RAYS_PER_GROUP - 1u) / RAYS_PER_GROUP;
  groups_x = min(groups, 65535u);
  groups_y = (groups + 65534u) / 65535u;
  groups_z = 1u;
}

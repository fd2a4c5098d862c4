/* scene_internal.h — what the scene's files share (not installed): the
 * schema's defaults (the table's, scene_schema.h, and the few it does not
 * bind), set by the JSON loader and by the C builder alike. */
#ifndef BS_SCENE_INTERNAL_H
#define BS_SCENE_INTERNAL_H

#include "bs_scene.h"

void bs__scene_defaults(bs_scene *s);
void bs__scene_body_defaults(bs_scene_body *b);
void bs__scene_material_defaults(bs_scene_material *m);
void bs__scene_obstacle_defaults(bs_scene_obstacle *o);
void bs__scene_qoi_defaults(bs_scene_qoi *q);

#endif

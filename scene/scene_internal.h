/* scene_internal.h — what the scene's files share (not installed): the
 * schema's defaults, set by the JSON loader and by the C builder alike. */
#ifndef BS_SCENE_INTERNAL_H
#define BS_SCENE_INTERNAL_H

#include "bs_scene.h"

void bs_scene_defaults_(bs_scene *s);
void bs_scene_body_defaults_(bs_scene_body *b);
void bs_scene_material_defaults_(bs_scene_material *m);
void bs_scene_obstacle_defaults_(bs_scene_obstacle *o);

#endif

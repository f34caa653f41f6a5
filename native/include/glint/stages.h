// Kept so that code which includes it goes on building: what it held is now
// in three headers, by what it is. New code includes the one it uses.
//   glint/backend.h     the Backend interface (the stages), TraceInputs, get_backend()
//   glint/material.h    the specular buffer's encoding: reflective, roughness, GGX alpha, cone
//   glint/validation.h  the input checks every backend runs first
#pragma once
#include "glint/backend.h"
#include "glint/material.h"
#include "glint/validation.h"

#include "screwfem/io/scene.h"

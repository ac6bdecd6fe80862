#include "screwfem/elements/rod.h"

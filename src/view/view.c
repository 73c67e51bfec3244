/* The viewer's application (see view.h). */
#include "view/view.h"

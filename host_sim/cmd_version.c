#include <stdio.h>

#include "commands.h"
#include "lsm_config.h"

int cmd_version(int argc, char **argv)
{
    (void)argc;
    (void)argv;
    printf("lissom-sim 0.1.0 (real type: %s)\n", LSM_REAL_IS_FLOAT ? "float" : "double");
    return 0;
}

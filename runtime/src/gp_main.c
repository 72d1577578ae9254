/* Entry point of a compiled mission: everything lives in gp_main (gp_link.c). */
#include "gp_link.h"

int main(int argc, char **argv)
{
    return gp_main(argc, argv);
}

/* A good plan of the Fig. 2 table (tests/fig2_mission.c) up to its checksum line: the plan
 * reader's tests change it one field at a time, the update's tests change it by updates. */
#ifndef FIG2_PLAN_H
#define FIG2_PLAN_H

#define GOOD_BODY                                                                   \
    "GPPLAN 3\n"                                                                    \
    "mission sampleMission\n"                                                       \
    "hash 5db9c7f6bccd8ec471713fb8071fb0f3aceb0069b185b69571c5783b1814d1b9\n"       \
    "computer ts7800 300\n"                                                         \
    "budget_j 180000\n"                                                             \
    "predicted_j 10203\n"                                                           \
    "components hotel pump ctd\n"                                                   \
    "assumptions 2\n"                                                               \
    "assume mission vehicle slocum_g2_shallow (default)\n"                          \
    "assume s2 planned at its expect upper bound (3600 s per visit)\n"              \
    "states 3\n"                                                                    \
    "state s1 300 600 0 1\n"                                                        \
    "predict 1000 2 19.8\n"                                                         \
    "energy 2410 1540 0\n"                                                          \
    "profile 0 1 0.454 230 0.31\n"                                                  \
    "end\n"                                                                         \
    "state s2 500 600 2 1\n"                                                        \
    "predict 1000 1 12.4\n"                                                         \
    "energy 2410 1585 240\n"                                                        \
    "sensor depth 60 0\n"                                                           \
    "sensor temp 60 15\n"                                                           \
    "profile 0 1 0.4 200 0.3\n"                                                     \
    "end\n"                                                                         \
    "state s3 300 600 0 1\n"                                                        \
    "predict 500 1 4.7\n"                                                           \
    "energy 1205 813 0\n"                                                           \
    "profile 0 1 0.454 230 0.31\n"                                                  \
    "end\n"

#endif /* FIG2_PLAN_H */

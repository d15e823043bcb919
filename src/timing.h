/* Wall-clock milliseconds (monotonic), for stage times. */
#ifndef VS_TIMING_H
#define VS_TIMING_H

double vs_now_ms(void);

#endif

/* ccmap_app platform configuration. */
#ifndef CCMAP_APP_PLATFORM_CFG_H
#define CCMAP_APP_PLATFORM_CFG_H

#define CCMAP_APP_PIPE_DEPTH 8 /* at most /proc/sys/fs/mqueue/msg_max (10) when not root */
#define CCMAP_APP_PIPE_NAME  "CCMAP_APP_PIPE"
#define CCMAP_APP_TABLE_FILE "/cf/ccmap_app_tbl.tbl" /* the parameter table loaded at start */

#endif

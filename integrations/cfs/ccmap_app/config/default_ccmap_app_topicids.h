/* ccmap_app topic IDs (mission scope). On a cpu the command message ID is
 * CFE_PLATFORM_CMD_TOPICID_TO_MIDV(topic) (0x1800 | topic on the sample mission) and the
 * telemetry ID CFE_PLATFORM_TLM_TOPICID_TO_MIDV(topic) (0x0800 | topic). cFE uses 0x00-0x11 and
 * the lab apps 0x80-0x86. The frame-ready topic is ccmap_frames' (ccmap_frames.h). */
#ifndef CCMAP_APP_TOPICIDS_H
#define CCMAP_APP_TOPICIDS_H

#define CFE_MISSION_CCMAP_APP_CMD_TOPICID     0xA0 /* ground commands */
#define CFE_MISSION_CCMAP_APP_SEND_HK_TOPICID 0xA1 /* the scheduler's housekeeping wake-up */
#define CFE_MISSION_CCMAP_APP_HK_TLM_TOPICID  0xA1 /* housekeeping telemetry */
#define CFE_MISSION_CCMAP_APP_PRODUCT_TLM_TOPICID 0xA3 /* hazard product summary (per PUBLISH) */

#endif

/* ccmap_frames: a ring of static frame slots shared by a producer (a camera app; the test's
 * ccmap_feed) and the consumer (ccmap_app), so that a CADRE frame (552,500 points, 6.6 MB) is
 * never copied through the software bus. A slot moves FREE -> FILLING (producer Acquire) ->
 * READY (producer Ready, gets a sequence number) -> BUSY (consumer Take with that slot and
 * sequence) -> FREE (consumer Release). Each step is one atomic compare-and-swap on the slot's
 * state, so a stale or forged FRAME_READY (wrong slot, old sequence) is refused, never mapped
 * twice, and a slot is never written while read. Single producer and single consumer per slot. */
#ifndef CCMAP_FRAMES_H
#define CCMAP_FRAMES_H

#include "cfe.h"
#include "cfe_core_api_base_msgids.h"

#define CCMAP_FRAMES_SLOTS      2u
#define CCMAP_FRAMES_MAX_POINTS 552500u /* 850 x 650 */

/* The frame-ready message: a command-type packet on the consumer's pipe. */
#ifndef CFE_MISSION_CCMAP_FRAMES_READY_TOPICID
#define CFE_MISSION_CCMAP_FRAMES_READY_TOPICID 0xA2
#endif
#define CCMAP_FRAMES_READY_MID CFE_PLATFORM_CMD_TOPICID_TO_MIDV(CFE_MISSION_CCMAP_FRAMES_READY_TOPICID)

typedef enum
{
    CCMAP_FRAMES_FREE    = 0,
    CCMAP_FRAMES_FILLING = 1,
    CCMAP_FRAMES_READY   = 2,
    CCMAP_FRAMES_BUSY    = 3
} CCMAP_FRAMES_State_t;

typedef struct
{
    uint32 State;          /* CCMAP_FRAMES_State_t, changed atomically only */
    uint32 Sequence;       /* set by Ready, 1, 2, ... over all slots */
    uint32 NumPoints;      /* points in Xyz, <= CCMAP_FRAMES_MAX_POINTS */
    float  Rotation[9];    /* sensor -> map, row-major: p_map = R p_sensor + t */
    float  Translation[3]; /* m, map frame */
    float  Xyz[3u * CCMAP_FRAMES_MAX_POINTS]; /* sensor-frame points, m (x forward, y left, z up) */
} CCMAP_FRAMES_Slot_t;

typedef struct
{
    uint32 Slot;
    uint32 Sequence;
} CCMAP_FRAMES_Ready_Payload_t;

typedef struct
{
    CFE_MSG_CommandHeader_t      CommandHeader;
    CCMAP_FRAMES_Ready_Payload_t Payload;
} CCMAP_FRAMES_ReadyMsg_t;

/* Library entry point (cFE startup script). */
int32 CCMAP_FRAMES_Init(void);

/* Producer: a FREE slot now FILLING and its index in *Slot; NULL when every slot is in use. */
CCMAP_FRAMES_Slot_t *CCMAP_FRAMES_Acquire(uint32 *Slot);
/* Producer: FILLING -> READY with the next sequence number in *Sequence. CFE_SUCCESS, or
 * CFE_ES_BAD_ARGUMENT for a bad index or a slot not FILLING. */
int32 CCMAP_FRAMES_Ready(uint32 Slot, uint32 *Sequence);
/* Consumer: READY with this sequence -> BUSY; the slot, or NULL (nothing changed) for a bad index,
 * a slot not READY or another sequence. */
const CCMAP_FRAMES_Slot_t *CCMAP_FRAMES_Take(uint32 Slot, uint32 Sequence);
/* Consumer after Take, or producer giving up a FILLING slot: back to FREE. */
void CCMAP_FRAMES_Release(uint32 Slot);

#endif

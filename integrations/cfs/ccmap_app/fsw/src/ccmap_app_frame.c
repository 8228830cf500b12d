/* ccmap_app frame handling: a FRAME_READY message names a ccmap_frames slot and its sequence; the
 * points are read where the producer wrote them (no copy), folded into the map, and the slot is
 * handed back. Kept in its own file so that it can be built alone against stubs (its aarch64
 * instruction count: integrations/cfs/test/frame_icount.c). */
#include <string.h>

#include "ccmap_app.h"
#include "ccmap_app_dispatch.h"
#include "ccmap_app_eventids.h"

static uint32 CCMAP_APP_Elapsed(OS_time_t From, OS_time_t To)
{
    int64 Us = OS_TimeGetTotalMicroseconds(OS_TimeSubtract(To, From));
    return (Us < 0) ? 0u : (Us > 0xFFFFFFFF ? 0xFFFFFFFFu : (uint32)Us);
}

void CCMAP_APP_FrameReady(const CFE_SB_Buffer_t *SBBufPtr)
{
    CCMAP_APP_HkTlm_Payload_t     *Hk = &CCMAP_APP_Data.HkTlm.Payload;
    const CCMAP_FRAMES_ReadyMsg_t *Msg;
    const CCMAP_FRAMES_Slot_t     *Slot;
    ccmap_pose                     Pose;
    ccmap_frame_counters           Counters;
    ccmap_status                   Status;
    OS_time_t                      Start;
    OS_time_t                      LibStart;
    OS_time_t                      LibEnd;
    OS_time_t                      End;

    OS_GetLocalTime(&Start);
    if (!CCMAP_APP_VerifyLength(&SBBufPtr->Msg, sizeof(CCMAP_FRAMES_ReadyMsg_t)))
    {
        ++Hk->FramesDropped;
        return;
    }
    Msg  = (const CCMAP_FRAMES_ReadyMsg_t *)SBBufPtr;
    Slot = CCMAP_FRAMES_Take(Msg->Payload.Slot, Msg->Payload.Sequence);
    if (Slot == NULL)
    {
        ++Hk->FramesDropped;
        CFE_EVS_SendEvent(CCMAP_APP_FRAME_ERR_EID, CFE_EVS_EventType_ERROR,
                          "CCMAP: frame refused: slot %lu sequence %lu not ready", (unsigned long)Msg->Payload.Slot,
                          (unsigned long)Msg->Payload.Sequence);
        return;
    }
    memcpy(Pose.rotation, Slot->Rotation, sizeof(Pose.rotation));
    memcpy(Pose.translation, Slot->Translation, sizeof(Pose.translation));

    OS_GetLocalTime(&LibStart);
    Status = ccmap_update_frame_sensor(CCMAP_APP_Data.Map, Slot->Xyz, Slot->NumPoints, &Pose, &Counters);
    OS_GetLocalTime(&LibEnd);
    CCMAP_FRAMES_Release(Msg->Payload.Slot);

    if (Status != CCMAP_OK)
    {
        Hk->LastStatus = Status;
        CFE_EVS_SendEvent(CCMAP_APP_UPDATE_ERR_EID, CFE_EVS_EventType_ERROR, "CCMAP: frame %lu refused: %s",
                          (unsigned long)Msg->Payload.Sequence, ccmap_status_string(Status));
    }
    else
    {
        memcpy(CCMAP_APP_Data.LastPose, Pose.translation, sizeof(CCMAP_APP_Data.LastPose));
    }
    OS_GetLocalTime(&End);
    Hk->LastLibraryUs = CCMAP_APP_Elapsed(LibStart, LibEnd);
    Hk->LastFrameUs   = CCMAP_APP_Elapsed(Start, End);
    if (Hk->LastFrameUs > Hk->MaxFrameUs)
    {
        Hk->MaxFrameUs = Hk->LastFrameUs;
    }
    if (Hk->LastFrameUs > Hk->CycleBudgetUs)
    {
        ++Hk->BudgetOverruns;
        CFE_EVS_SendEvent(CCMAP_APP_BUDGET_ERR_EID, CFE_EVS_EventType_ERROR,
                          "CCMAP: frame %lu took %lu us, over the %lu us budget", (unsigned long)Msg->Payload.Sequence,
                          (unsigned long)Hk->LastFrameUs, (unsigned long)Hk->CycleBudgetUs);
    }
}

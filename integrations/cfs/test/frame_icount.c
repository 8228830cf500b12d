/* The aarch64 instruction count of ccmap_app's own frame handling: CCMAP_APP_FrameReady
 * (ccmap_app_frame.c) with the length check of ccmap_app_dispatch.c and the slot hand-over of
 * ccmap_frames.c, all three compiled as they are, around a stubbed library call. Counted under
 * QEMU with the project's plugin (tools/qemu-icount) by run_cfs_test.py, between the marker
 * instructions of tools/qemu-icount/icount_marker_encoding.h: region 1 brackets one frame-ready
 * message handled (frame taken, mapped by the stub, released, timed, counted), region 2 one
 * forged message refused. What is not the app's own is stubbed: cFE's message accessors and event
 * service, OSAL's clock and the library (ccmap_update_frame_sensor); the stubs' few instructions
 * each are inside the count (an upper bound of the app's own). It also prints the aarch64 sizes
 * of the packets the ground module decodes. */
#include <stdarg.h>
#include <stdio.h>
#include <string.h>

#include "ccmap_app.h"
#include "ccmap_app_cmds.h"
#include "ccmap_app_dispatch.h"

#define MARK_BEGIN(id) __asm__ volatile(".inst 0xD280001F | (" #id " << 5)" ::: "memory")
#define MARK_END(id)   __asm__ volatile(".inst 0xD2A0001F | (" #id " << 5)" ::: "memory")

CCMAP_APP_Data_t CCMAP_APP_Data;

/* ---- stubs: cFE, OSAL and the library ---- */
static size_t MsgSize;
CFE_Status_t CFE_MSG_GetSize(const CFE_MSG_Message_t *MsgPtr, CFE_MSG_Size_t *Size)
{
    (void)MsgPtr;
    *Size = MsgSize;
    return CFE_SUCCESS;
}
CFE_Status_t CFE_MSG_GetMsgId(const CFE_MSG_Message_t *MsgPtr, CFE_SB_MsgId_t *MsgId)
{
    (void)MsgPtr;
    *MsgId = CFE_SB_ValueToMsgId(CCMAP_FRAMES_READY_MID);
    return CFE_SUCCESS;
}
CFE_Status_t CFE_MSG_GetFcnCode(const CFE_MSG_Message_t *MsgPtr, CFE_MSG_FcnCode_t *FcnCode)
{
    (void)MsgPtr;
    *FcnCode = 0;
    return CFE_SUCCESS;
}
CFE_Status_t CFE_EVS_SendEvent(uint16 EventID, uint16 EventType, const char *Spec, ...)
{
    (void)EventID;
    (void)EventType;
    (void)Spec;
    return CFE_SUCCESS;
}
void OS_printf(const char *string, ...)
{
    (void)string;
}
static int64 Clock;
int32 OS_GetLocalTime(OS_time_t *time_struct)
{
    Clock += 10;
    *time_struct = OS_TimeFromTotalMicroseconds(Clock);
    return OS_SUCCESS;
}
ccmap_status ccmap_update_frame_sensor(ccmap_map *map, const float *xyz, size_t n, const ccmap_pose *pose,
                                       ccmap_frame_counters *counters)
{
    (void)map;
    (void)xyz;
    (void)n;
    (void)pose;
    memset(counters, 0, sizeof(*counters));
    return CCMAP_OK;
}
const char *ccmap_status_string(ccmap_status status)
{
    (void)status;
    return "";
}
/* The dispatcher's other handlers: never called here. */
void CCMAP_APP_NoopCmd(const CCMAP_APP_NoopCmd_t *Msg) { (void)Msg; }
void CCMAP_APP_ResetCountersCmd(const CCMAP_APP_ResetCountersCmd_t *Msg) { (void)Msg; }
void CCMAP_APP_ClearCmd(const CCMAP_APP_ClearCmd_t *Msg) { (void)Msg; }
void CCMAP_APP_SaveCmd(const CCMAP_APP_FileCmd_t *Msg) { (void)Msg; }
void CCMAP_APP_LoadCmd(const CCMAP_APP_FileCmd_t *Msg) { (void)Msg; }
void CCMAP_APP_LoadTableCmd(const CCMAP_APP_FileCmd_t *Msg) { (void)Msg; }
void CCMAP_APP_PublishCmd(const CCMAP_APP_PublishCmd_t *Msg) { (void)Msg; }
void CCMAP_APP_SendHkCmd(const CCMAP_APP_SendHkCmd_t *Msg) { (void)Msg; }

/* ---- the harness: 8 frames handed over and mapped, then 8 forged messages refused ---- */
int main(void)
{
    static CCMAP_FRAMES_ReadyMsg_t Msg;
    uint32                         Slot;
    uint32                         Sequence;
    CCMAP_FRAMES_Slot_t           *SlotPtr;
    int                            i;

    (void)CCMAP_FRAMES_Init();
    CCMAP_APP_Data.HkTlm.Payload.CycleBudgetUs = 80000;
    MsgSize                                    = sizeof(Msg);
    for (i = 0; i < 8; ++i)
    {
        SlotPtr = CCMAP_FRAMES_Acquire(&Slot);
        if (SlotPtr == NULL || CCMAP_FRAMES_Ready(Slot, &Sequence) != CFE_SUCCESS)
        {
            return 1;
        }
        SlotPtr->NumPoints       = CCMAP_FRAMES_MAX_POINTS;
        SlotPtr->Rotation[0]     = 1.0f;
        SlotPtr->Rotation[4]     = 1.0f;
        SlotPtr->Rotation[8]     = 1.0f;
        Msg.Payload.Slot         = Slot;
        Msg.Payload.Sequence     = Sequence;
        MARK_BEGIN(1);
        CCMAP_APP_TaskPipe((const CFE_SB_Buffer_t *)(void *)&Msg);
        MARK_END(1);
    }
    for (i = 0; i < 8; ++i)
    {
        Msg.Payload.Sequence = 12345u;
        MARK_BEGIN(2);
        CCMAP_APP_TaskPipe((const CFE_SB_Buffer_t *)(void *)&Msg);
        MARK_END(2);
    }
    /* The payload sizes the ground module's formats must match (run_cfs_test.py compares). */
    printf("sizes hk=%u product=%u table=%u\n", (unsigned)sizeof(CCMAP_APP_HkTlm_Payload_t),
           (unsigned)sizeof(CCMAP_APP_ProductTlm_Payload_t), (unsigned)sizeof(CCMAP_APP_ParamTable_t));
    /* Every frame taken and released, every forged one dropped. */
    return (CCMAP_APP_Data.HkTlm.Payload.FramesDropped == 8u && CCMAP_APP_Data.HkTlm.Payload.BudgetOverruns == 0u)
               ? 0
               : 1;
}

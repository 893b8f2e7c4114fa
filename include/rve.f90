! rve.f90 -- Fortran 2008 interface of mesorve: module `rve`, with a bind(C) interface for
! every function of include/rve.h, its constants, the `rve_info` and `rve_point_report`
! types, and thin convenience wrappers (suffix `_f`). Hand-written beside the generated header;
! scripts/test-fortran fails when the two disagree (names, argument lists, value or
! reference, const-ness, widths, struct layout, constant values).
!
! Build: a .mod file is specific to one compiler (and version), so compile this source
! with the compiler of the host code and link its object file with the library:
!
!   gfortran -c rve.f90                       ! rve.mod + rve.o (or add rve.f90 to a build)
!   gfortran -c host.f90                      ! host.f90: `use rve`
!   gfortran host.o rve.o -lrve               ! + -L, rpath; see `pkg-config --libs rve`
!
! Conventions (the same as the C interface; see include/rve.h for each function):
! - strain  = [eps_xx, eps_yy, gamma_xy] with ENGINEERING shear gamma_xy = 2 eps_xy;
!   stress  = [s_xx, s_yy, s_xy], in the scene's units.
! - TANGENT. The C function writes 9 doubles row-major: tangent[3*i + j] = d s_i / d e_j
!   (0-based). Received as `real(c_double) :: d(3,3)` (column-major), the raw interfaces
!   below (rve_update, rve_update_ex, rve_update_batch*) give
!         d(j, i) = d s_i / d e_j,   i.e. d = TRANSPOSE of the Jacobian
!   (equal only when the tangent is symmetric: do not rely on it; the consistent tangent
!   need not be symmetric, and on the paper's cycle its transpose differs in the last
!   bits). The wrapper rve_update_f transposes for you and returns the UMAT orientation
!   ddsdde(i, j) = d s_i / d e_j (Abaqus DDSDDE).
! - Handles are `integer(c_int64_t)` ids (C: RveHandle = int64_t), never pointers; 0 is
!   never valid. Ids lie in [2^32, 2^52), so they are exact in a `real(c_double)`: a UMAT
!   may keep one in a STATEV slot, `statev(1) = real(h, c_double)` and
!   `h = int(statev(1), c_int64_t)`.
! - Fortran has no unsigned integers: C uint32_t is `integer(c_int32_t)` here (status
!   codes and versions are far below 2^31), uint64_t is `integer(c_int64_t)`, size_t is
!   `integer(c_size_t)`, the state bytes (uint8_t) are `integer(c_int8_t)`.
! - Every call returns a status, `integer(c_int32_t)`: compare it with RVE_STATUS_*.
!   rve_last_error_f() gives the message of the last failed call on this thread.
! - Strings are NUL-terminated `character(kind=c_char)` arrays: pass `trim(s)//c_null_char`
!   (a character scalar of kind c_char may be passed for the array), or use the wrappers.
! - Outputs that C writes only on success (handles, stress, tangent, sizes, info) are
!   `intent(inout)`: after a failure they keep the value they had, as in C.
! - Pointers that C accepts as NULL (rve_update's tangent with RVE_TANGENT_REQUEST_NONE,
!   rve_update_ex's info, rve_init_text's base_dir, rve_last_error's buffer) are declared
!   as arrays/variables here: pass a dummy (tangent, info), use rve_init_text_f (base_dir
!   absent = working directory) and rve_last_error_f. rve_init's scene_path, whose NULL
!   means the embedded paper RVE, is a `type(c_ptr), value`: use rve_init_f.
!
! Thread safety as in C: distinct instances may be updated from distinct threads
! (OpenMP); one instance, one thread at a time.
module rve
  use, intrinsic :: iso_c_binding, only: c_char, c_double, c_int, c_int8_t, c_int32_t, &
      c_int64_t, c_null_char, c_ptr, c_size_t, c_associated, c_f_pointer, c_loc, c_null_ptr
  implicit none
  private

  ! Kinds, re-exported so a host needs only `use rve`.
  public :: c_char, c_double, c_int8_t, c_int32_t, c_int64_t, c_null_char, c_ptr, c_size_t

  ! Version of include/rve.h this module matches (C: RVE_VERSION, RVE_VERSION_MAJOR/MINOR/
  ! PATCH, RVE_ABI_VERSION; renamed where Fortran's case-insensitive names would clash
  ! with the functions rve_version and rve_abi_version). A host must not use a library
  ! whose rve_abi_version() differs from RVE_MODULE_ABI_VERSION.
  character(len=*), parameter, public :: RVE_MODULE_VERSION = "0.4.0"
  integer(c_int32_t), parameter, public :: RVE_VERSION_MAJOR = 0
  integer(c_int32_t), parameter, public :: RVE_VERSION_MINOR = 4
  integer(c_int32_t), parameter, public :: RVE_VERSION_PATCH = 0
  integer(c_int32_t), parameter, public :: RVE_MODULE_ABI_VERSION = 0

  ! RveStatus: status code of a call (stable numbers, never reused).
  enum, bind(c)
    enumerator :: RVE_STATUS_OK = 0                ! success
    enumerator :: RVE_STATUS_NULL_ARGUMENT = 1     ! a required pointer was NULL
    enumerator :: RVE_STATUS_BAD_SCENE = 2         ! scene unreadable, unparsable, invalid
    enumerator :: RVE_STATUS_MESH_FAILED = 3       ! placement, meshing or import failed
    enumerator :: RVE_STATUS_BAD_HANDLE = 4        ! 0, freed or foreign handle
    enumerator :: RVE_STATUS_NON_FINITE_STRAIN = 5 ! NaN or infinite strain component
    enumerator :: RVE_STATUS_ABSURD_STRAIN = 6     ! |component| > 0.1
    enumerator :: RVE_STATUS_SOLVER_FAILED = 7     ! retry with a smaller increment (PNEWDT)
    enumerator :: RVE_STATUS_NO_TRIAL = 8          ! commit without a successful update
    enumerator :: RVE_STATUS_INSTANCE_BUSY = 9     ! instance in use by another thread
    enumerator :: RVE_STATUS_INVALID_ARGUMENT = 10 ! bad value (tangent request, index...)
    enumerator :: RVE_STATUS_BUFFER_TOO_SMALL = 11 ! required size written where documented
    enumerator :: RVE_STATUS_BAD_STATE = 12        ! bytes are not a mesorve state
    enumerator :: RVE_STATUS_STATE_VERSION = 13    ! unsupported state format version
    enumerator :: RVE_STATUS_STATE_MISMATCH = 14   ! state of another scene's model
    enumerator :: RVE_STATUS_BATCH_FAILED = 15     ! see the batch's statuses array
    enumerator :: RVE_STATUS_WRITE_FAILED = 16     ! output file not written (rve_write_vtk)
    enumerator :: RVE_STATUS_LINEAR_ALGEBRA_FAILED = 17 ! symbolic analysis of the RVE matrix
    enumerator :: RVE_STATUS_INTERNAL = 98         ! a bug: please report it
    enumerator :: RVE_STATUS_PANIC = 99            ! a bug: please report it
  end enum

  ! RveTangentRequest: what tangent rve_update returns (an int32_t argument).
  enum, bind(c)
    enumerator :: RVE_TANGENT_REQUEST_CONSISTENT = 0 ! consistent homogenized tangent
    enumerator :: RVE_TANGENT_REQUEST_NONE = 1       ! stress only; tangent not written
    enumerator :: RVE_TANGENT_REQUEST_ELASTIC = 2    ! elastic tangent of the virgin RVE
  end enum

  ! RveReliability: the `reliability` field of rve_info.
  enum, bind(c)
    enumerator :: RVE_RELIABILITY_FAILED = 0     ! only suggested_step_ratio is meaningful
    enumerator :: RVE_RELIABILITY_RELIABLE = 1   ! converged in one step
    enumerator :: RVE_RELIABILITY_SUBSTEPPED = 2 ! converged after bisecting the increment
  end enum

  public :: RVE_STATUS_OK, RVE_STATUS_NULL_ARGUMENT, RVE_STATUS_BAD_SCENE, &
      RVE_STATUS_MESH_FAILED, RVE_STATUS_BAD_HANDLE, RVE_STATUS_NON_FINITE_STRAIN, &
      RVE_STATUS_ABSURD_STRAIN, RVE_STATUS_SOLVER_FAILED, RVE_STATUS_NO_TRIAL, &
      RVE_STATUS_INSTANCE_BUSY, RVE_STATUS_INVALID_ARGUMENT, RVE_STATUS_BUFFER_TOO_SMALL, &
      RVE_STATUS_BAD_STATE, RVE_STATUS_STATE_VERSION, RVE_STATUS_STATE_MISMATCH, &
      RVE_STATUS_BATCH_FAILED, RVE_STATUS_WRITE_FAILED, RVE_STATUS_LINEAR_ALGEBRA_FAILED, &
      RVE_STATUS_INTERNAL, RVE_STATUS_PANIC
  public :: RVE_TANGENT_REQUEST_CONSISTENT, RVE_TANGENT_REQUEST_NONE, &
      RVE_TANGENT_REQUEST_ELASTIC
  public :: RVE_RELIABILITY_FAILED, RVE_RELIABILITY_RELIABLE, RVE_RELIABILITY_SUBSTEPPED

  ! RveInfo: extra outputs of rve_update_ex, field for field.
  type, bind(c), public :: rve_info
    integer(c_int32_t) :: iterations          ! uint32_t: Newton corrections, all sub-steps
    integer(c_int32_t) :: substeps            ! uint32_t: accepted sub-steps (1: one go)
    integer(c_int32_t) :: factorizations      ! uint32_t: numeric factorizations
    integer(c_int32_t) :: reliability         ! an RVE_RELIABILITY_* value
    real(c_double) :: suggested_step_ratio    ! < 1: redo smaller (failure, step check, tolerance); > 1: may grow
    real(c_double) :: s_zz                    ! out-of-plane stress (plane strain; else 0)
  end type rve_info

  ! RvePointReport: per-point report of rve_update_batch_timed, field for field.
  type, bind(c), public :: rve_point_report
    integer(c_int32_t) :: status              ! uint32_t: this point's RVE_STATUS_* value
    integer(c_int32_t) :: iterations          ! uint32_t: as rve_info
    integer(c_int32_t) :: substeps            ! uint32_t: as rve_info
    integer(c_int32_t) :: factorizations      ! uint32_t: as rve_info
    integer(c_int32_t) :: reliability         ! an RVE_RELIABILITY_* value
    integer(c_int32_t) :: shared_from         ! uint32_t: 0 (answer sharing: not yet)
    real(c_double) :: suggested_step_ratio    ! < 1: redo smaller; 1 otherwise
    real(c_double) :: error_estimate          ! 0 (no error estimate yet)
    real(c_double) :: s_zz                    ! as rve_info
  end type rve_point_report

  ! ---- bind(C) interfaces: one per function of include/rve.h, in the header's order ----
  public :: rve_update_batch, rve_update_batch_timed, rve_last_error, rve_init, rve_init_file, rve_init_text, &
      rve_clone_model, rve_clone_for_element, rve_update_ex, rve_update_timed, rve_update, rve_commit, rve_revert, rve_reset, &
      rve_free, rve_fast_updates, rve_state_size, rve_state_save, rve_state_load, rve_write_vtk, rve_path_len, &
      rve_path_point, rve_model_builds, rve_status_message, rve_umat, rve_version, &
      rve_version_number, rve_abi_version

  interface
    ! Item k (1-based) is rve_update(handles(k), strains(:,k), stresses(:,k),
    ! tangents(:,:,k), tangent_request); statuses(k) receives its status. tangents(:,:,k)
    ! is the TRANSPOSE of the Jacobian (see above). nthreads: 1 = calling thread,
    ! k > 1 = a pool of k threads, 0 = one per core.
    function rve_update_batch(handles, n, strains, stresses, tangents, statuses, &
        tangent_request, nthreads) bind(c, name="rve_update_batch") result(status)
      import :: c_int64_t, c_size_t, c_double, c_int32_t
      integer(c_int64_t), intent(in) :: handles(*)
      integer(c_size_t), value, intent(in) :: n
      real(c_double), intent(in) :: strains(3, *)
      real(c_double), intent(inout) :: stresses(3, *)
      real(c_double), intent(inout) :: tangents(3, 3, *)
      integer(c_int32_t), intent(inout) :: statuses(*)
      integer(c_int32_t), value, intent(in) :: tangent_request
      integer(c_size_t), value, intent(in) :: nthreads
      integer(c_int32_t) :: status
    end function rve_update_batch

    ! rve_update_batch over a host time increment dtime (as rve_update_timed), with a
    ! report per point: reports(k) and messages((k-1)*message_len+1 : k*message_len), the
    ! failure's message of point k, NUL-terminated, truncated ("" after a success). C
    ! accepts NULL for both: here pass a dummy report and a one-character buffer with
    ! message_len = 0 (nothing written).
    function rve_update_batch_timed(handles, n, strains, dtime, stresses, tangents, &
        tangent_request, reports, messages, message_len, nthreads) &
        bind(c, name="rve_update_batch_timed") result(status)
      import :: c_int64_t, c_size_t, c_double, c_int32_t, c_char, rve_point_report
      integer(c_int64_t), intent(in) :: handles(*)
      integer(c_size_t), value, intent(in) :: n
      real(c_double), intent(in) :: strains(3, *)
      real(c_double), value, intent(in) :: dtime
      real(c_double), intent(inout) :: stresses(3, *)
      real(c_double), intent(inout) :: tangents(3, 3, *)
      integer(c_int32_t), value, intent(in) :: tangent_request
      type(rve_point_report), intent(inout) :: reports(*)
      character(kind=c_char), intent(inout) :: messages(*)
      integer(c_size_t), value, intent(in) :: message_len
      integer(c_size_t), value, intent(in) :: nthreads
      integer(c_int32_t) :: status
    end function rve_update_batch_timed

    ! Copies the last error message of this thread into buf(1:len), NUL-terminated when
    ! len > 0; returns the full length without the NUL (len = 0: only the length).
    function rve_last_error(buf, len) bind(c, name="rve_last_error") result(full_len)
      import :: c_char, c_size_t
      character(kind=c_char), intent(inout) :: buf(*)
      integer(c_size_t), value, intent(in) :: len
      integer(c_size_t) :: full_len
    end function rve_last_error

    ! scene_path: c_loc of a NUL-terminated character array, or c_null_ptr for the paper's
    ! RVE embedded in the library (use rve_init_f). out_handle written only on success.
    function rve_init(scene_path, out_handle) bind(c, name="rve_init") result(status)
      import :: c_ptr, c_int64_t, c_int32_t
      type(c_ptr), value, intent(in) :: scene_path
      integer(c_int64_t), intent(inout) :: out_handle
      integer(c_int32_t) :: status
    end function rve_init

    ! path: NUL-terminated. out_handle written only on success.
    function rve_init_file(path, out_handle) bind(c, name="rve_init_file") result(status)
      import :: c_char, c_int64_t, c_int32_t
      character(kind=c_char), intent(in) :: path(*)
      integer(c_int64_t), intent(inout) :: out_handle
      integer(c_int32_t) :: status
    end function rve_init_file

    ! toml_text, base_dir: NUL-terminated (C also accepts base_dir = NULL, the working
    ! directory: use rve_init_text_f). out_handle written only on success.
    function rve_init_text(toml_text, base_dir, out_handle) &
        bind(c, name="rve_init_text") result(status)
      import :: c_char, c_int64_t, c_int32_t
      character(kind=c_char), intent(in) :: toml_text(*)
      character(kind=c_char), intent(in) :: base_dir(*)
      integer(c_int64_t), intent(inout) :: out_handle
      integer(c_int32_t) :: status
    end function rve_init_text

    function rve_clone_model(h, out_handle) bind(c, name="rve_clone_model") result(status)
      import :: c_int64_t, c_int32_t
      integer(c_int64_t), value, intent(in) :: h
      integer(c_int64_t), intent(inout) :: out_handle
      integer(c_int32_t) :: status
    end function rve_clone_model

    ! A virgin instance of h's scene regularized for a host element of length
    ! element_length (the scene needs effects.regularization; docs/fracture.md).
    function rve_clone_for_element(h, element_length, out_handle) &
        bind(c, name="rve_clone_for_element") result(status)
      import :: c_int64_t, c_double, c_int32_t
      integer(c_int64_t), value, intent(in) :: h
      real(c_double), value, intent(in) :: element_length
      integer(c_int64_t), intent(inout) :: out_handle
      integer(c_int32_t) :: status
    end function rve_clone_for_element

    ! Trial update. tangent(3,3) receives the TRANSPOSE of d stress / d strain (see above);
    ! pass any 3x3 array with RVE_TANGENT_REQUEST_NONE (not written). stress and tangent
    ! written only on success; info on success and on RVE_STATUS_SOLVER_FAILED.
    function rve_update_ex(h, strain, stress, tangent, tangent_request, info) &
        bind(c, name="rve_update_ex") result(status)
      import :: c_int64_t, c_double, c_int32_t, rve_info
      integer(c_int64_t), value, intent(in) :: h
      real(c_double), intent(in) :: strain(3)
      real(c_double), intent(inout) :: stress(3)
      real(c_double), intent(inout) :: tangent(3, 3)
      integer(c_int32_t), value, intent(in) :: tangent_request
      type(rve_info), intent(inout) :: info
      integer(c_int32_t) :: status
    end function rve_update_ex

    ! rve_update_ex over a host time increment dtime (the UMAT's DTIME; <= 0: none given).
    ! Implicit integration ignores it; IMPL-EX scales its extrapolation by dtime / dtime_n.
    ! tangent(3,3) is the TRANSPOSE (see above).
    function rve_update_timed(h, strain, dtime, stress, tangent, tangent_request, info) &
        bind(c, name="rve_update_timed") result(status)
      import :: c_int64_t, c_double, c_int32_t, rve_info
      integer(c_int64_t), value, intent(in) :: h
      real(c_double), intent(in) :: strain(3)
      real(c_double), value, intent(in) :: dtime
      real(c_double), intent(inout) :: stress(3)
      real(c_double), intent(inout) :: tangent(3, 3)
      integer(c_int32_t), value, intent(in) :: tangent_request
      type(rve_info), intent(inout) :: info
      integer(c_int32_t) :: status
    end function rve_update_timed

    ! rve_update_ex without info. tangent(3,3) is the TRANSPOSE (see above).
    function rve_update(h, strain, stress, tangent, tangent_request) &
        bind(c, name="rve_update") result(status)
      import :: c_int64_t, c_double, c_int32_t
      integer(c_int64_t), value, intent(in) :: h
      real(c_double), intent(in) :: strain(3)
      real(c_double), intent(inout) :: stress(3)
      real(c_double), intent(inout) :: tangent(3, 3)
      integer(c_int32_t), value, intent(in) :: tangent_request
      integer(c_int32_t) :: status
    end function rve_update

    ! Accepts the last successful trial: the end of a macro increment.
    function rve_commit(h) bind(c, name="rve_commit") result(status)
      import :: c_int64_t, c_int32_t
      integer(c_int64_t), value, intent(in) :: h
      integer(c_int32_t) :: status
    end function rve_commit

    ! Discards the last trial.
    function rve_revert(h) bind(c, name="rve_revert") result(status)
      import :: c_int64_t, c_int32_t
      integer(c_int64_t), value, intent(in) :: h
      integer(c_int32_t) :: status
    end function rve_revert

    ! Back to the virgin state.
    function rve_reset(h) bind(c, name="rve_reset") result(status)
      import :: c_int64_t, c_int32_t
      integer(c_int64_t), value, intent(in) :: h
      integer(c_int32_t) :: status
    end function rve_reset

    ! Frees an instance (rve_free(0) is a no-op); its id never becomes valid again.
    function rve_free(h) bind(c, name="rve_free") result(status)
      import :: c_int64_t, c_int32_t
      integer(c_int64_t), value, intent(in) :: h
      integer(c_int32_t) :: status
    end function rve_free

    ! Bytes that rve_state_save needs now (depends on the state: query before each save).
    ! Updates of the instance answered without an RVE solve (fast path, repeats).
    function rve_fast_updates(h, count) bind(c, name="rve_fast_updates") result(status)
      import :: c_int64_t, c_int32_t
      integer(c_int64_t), value, intent(in) :: h
      integer(c_int64_t), intent(inout) :: count
      integer(c_int32_t) :: status
    end function rve_fast_updates

    function rve_state_size(h, size) bind(c, name="rve_state_size") result(status)
      import :: c_int64_t, c_size_t, c_int32_t
      integer(c_int64_t), value, intent(in) :: h
      integer(c_size_t), intent(inout) :: size
      integer(c_int32_t) :: status
    end function rve_state_size

    ! Committed state into buf(1:len); written = byte count (or the required size with
    ! RVE_STATUS_BUFFER_TOO_SMALL).
    function rve_state_save(h, buf, len, written) bind(c, name="rve_state_save") &
        result(status)
      import :: c_int64_t, c_int8_t, c_size_t, c_int32_t
      integer(c_int64_t), value, intent(in) :: h
      integer(c_int8_t), intent(inout) :: buf(*)
      integer(c_size_t), value, intent(in) :: len
      integer(c_size_t), intent(inout) :: written
      integer(c_int32_t) :: status
    end function rve_state_save

    ! Replaces the committed state by buf(1:len) (from rve_state_save, same scene).
    function rve_state_load(h, buf, len) bind(c, name="rve_state_load") result(status)
      import :: c_int64_t, c_int8_t, c_size_t, c_int32_t
      integer(c_int64_t), value, intent(in) :: h
      integer(c_int8_t), intent(in) :: buf(*)
      integer(c_size_t), value, intent(in) :: len
      integer(c_int32_t) :: status
    end function rve_state_load

    ! Writes the committed state as a ParaView .vtu file; path NUL-terminated
    ! (path // c_null_char). The instance is unchanged. RVE_STATUS_WRITE_FAILED when the
    ! file cannot be written.
    function rve_write_vtk(h, path) bind(c, name="rve_write_vtk") result(status)
      import :: c_int64_t, c_char, c_int32_t
      integer(c_int64_t), value, intent(in) :: h
      character(kind=c_char), intent(in) :: path(*)
      integer(c_int32_t) :: status
    end function rve_write_vtk

    ! Number of increments of the scene's [[path]].
    function rve_path_len(h, n) bind(c, name="rve_path_len") result(status)
      import :: c_int64_t, c_size_t, c_int32_t
      integer(c_int64_t), value, intent(in) :: h
      integer(c_size_t), intent(inout) :: n
      integer(c_int32_t) :: status
    end function rve_path_len

    ! Macro strain of increment i (0-BASED, i < rve_path_len), as `rve run` computes it.
    function rve_path_point(h, i, strain) bind(c, name="rve_path_point") result(status)
      import :: c_int64_t, c_size_t, c_double, c_int32_t
      integer(c_int64_t), value, intent(in) :: h
      integer(c_size_t), value, intent(in) :: i
      real(c_double), intent(inout) :: strain(3)
      integer(c_int32_t) :: status
    end function rve_path_point

    ! Number of models (meshes) built by this process (diagnostic of model sharing).
    function rve_model_builds() bind(c, name="rve_model_builds") result(n)
      import :: c_int64_t
      integer(c_int64_t) :: n
    end function rve_model_builds

    ! Static NUL-terminated description of a status code: use rve_status_message_f.
    function rve_status_message(code) bind(c, name="rve_status_message") result(msg)
      import :: c_int32_t, c_ptr
      integer(c_int32_t), value, intent(in) :: code
      type(c_ptr) :: msg
    end function rve_status_message

    ! The Abaqus UMAT (the library also exports it as umat_ and UMAT): a host calls
    ! `umat` with Abaqus's argument list; this binding names it in Fortran and makes the
    ! hidden length of cmname explicit. Conventions: README, "Use it from an FE code".
    subroutine rve_umat(stress, statev, ddsdde, sse, spd, scd, rpl, ddsddt, drplde, &
        drpldt, stran, dstran, time, dtime, temp, dtemp, predef, dpred, cmname, ndi, nshr, &
        ntens, nstatv, props, nprops, coords, drot, pnewdt, celent, dfgrd0, dfgrd1, noel, &
        npt, layer, kspt, kstep, kinc, cmname_len) bind(c, name="rve_umat")
      import :: c_double, c_char, c_int, c_size_t
      real(c_double), intent(inout) :: stress(*), statev(*), ddsdde(*)
      real(c_double), intent(inout) :: sse, spd, scd, rpl, ddsddt(*), drplde(*), drpldt
      real(c_double), intent(in) :: stran(*), dstran(*), time(2), dtime, temp, dtemp
      real(c_double), intent(in) :: predef(*), dpred(*)
      character(kind=c_char), intent(in) :: cmname(*)
      integer(c_int), intent(in) :: ndi, nshr, ntens, nstatv
      real(c_double), intent(in) :: props(*)
      integer(c_int), intent(in) :: nprops
      real(c_double), intent(in) :: coords(3), drot(3, 3)
      real(c_double), intent(inout) :: pnewdt
      real(c_double), intent(in) :: celent, dfgrd0(3, 3), dfgrd1(3, 3)
      integer(c_int), intent(in) :: noel, npt, layer, kspt, kstep, kinc
      integer(c_size_t), value, intent(in) :: cmname_len
    end subroutine rve_umat

    ! Static NUL-terminated "major.minor.patch": use rve_version_f.
    function rve_version() bind(c, name="rve_version") result(version)
      import :: c_ptr
      type(c_ptr) :: version
    end function rve_version

    ! major * 10000 + minor * 100 + patch.
    function rve_version_number() bind(c, name="rve_version_number") result(number)
      import :: c_int32_t
      integer(c_int32_t) :: number
    end function rve_version_number

    ! ABI version of the library: must equal RVE_MODULE_ABI_VERSION.
    function rve_abi_version() bind(c, name="rve_abi_version") result(abi)
      import :: c_int32_t
      integer(c_int32_t) :: abi
    end function rve_abi_version
  end interface

  ! ---- Fortran convenience wrappers ----
  public :: rve_init_f, rve_init_file_f, rve_init_text_f, rve_update_f, rve_last_error_f, &
      rve_status_message_f, rve_version_f

contains

  ! rve_init with a Fortran string (trailing blanks removed, NUL appended), or without
  ! scene_path (call rve_init_f(handle=h)) for the paper's RVE embedded in the library.
  function rve_init_f(scene_path, handle) result(status)
    character(len=*), intent(in), optional :: scene_path
    integer(c_int64_t), intent(inout) :: handle
    integer(c_int32_t) :: status
    character(kind=c_char), allocatable, target :: path(:)
    integer :: i, n
    if (present(scene_path)) then
      n = len_trim(scene_path)
      allocate (path(n + 1))
      do i = 1, n
        path(i) = scene_path(i:i)
      end do
      path(n + 1) = c_null_char
      status = rve_init(c_loc(path), handle)
    else
      status = rve_init(c_null_ptr, handle)
    end if
  end function rve_init_f

  ! rve_init_file with a Fortran string: trailing blanks removed, NUL appended.
  function rve_init_file_f(path, handle) result(status)
    character(len=*), intent(in) :: path
    integer(c_int64_t), intent(inout) :: handle
    integer(c_int32_t) :: status
    status = rve_init_file(trim(path) // c_null_char, handle)
  end function rve_init_file_f

  ! rve_init_text with a Fortran string (kept as is, NUL appended). Relative paths in the
  ! scene resolve against base_dir (trailing blanks removed), by default the working
  ! directory (as C's base_dir = NULL).
  function rve_init_text_f(toml_text, handle, base_dir) result(status)
    character(len=*), intent(in) :: toml_text
    integer(c_int64_t), intent(inout) :: handle
    character(len=*), intent(in), optional :: base_dir
    integer(c_int32_t) :: status
    if (present(base_dir)) then
      status = rve_init_text(toml_text // c_null_char, trim(base_dir) // c_null_char, handle)
    else
      status = rve_init_text(toml_text // c_null_char, "." // c_null_char, handle)
    end if
  end function rve_init_text_f

  ! Trial update returning the tangent in the UMAT orientation:
  !   ddsdde(i, j) = d stress_i / d strain_j     (Abaqus DDSDDE; the raw C array transposed)
  ! tangent_request: RVE_TANGENT_REQUEST_* (default CONSISTENT; with NONE ddsdde is not
  ! written). info (optional): as rve_update_ex. Outputs written as in C: stress and
  ! ddsdde only on success, info on success and on RVE_STATUS_SOLVER_FAILED.
  function rve_update_f(h, strain, stress, ddsdde, tangent_request, info) result(status)
    integer(c_int64_t), intent(in) :: h
    real(c_double), intent(in) :: strain(3)
    real(c_double), intent(inout) :: stress(3)
    real(c_double), intent(inout) :: ddsdde(3, 3)
    integer(c_int32_t), intent(in), optional :: tangent_request
    type(rve_info), intent(inout), optional :: info
    integer(c_int32_t) :: status
    integer(c_int32_t) :: request
    real(c_double) :: row_major(3, 3)
    type(rve_info) :: local_info
    request = RVE_TANGENT_REQUEST_CONSISTENT
    if (present(tangent_request)) request = tangent_request
    if (present(info)) local_info = info
    status = rve_update_ex(h, strain, stress, row_major, request, local_info)
    if (present(info)) info = local_info
    if (status == RVE_STATUS_OK .and. request /= RVE_TANGENT_REQUEST_NONE) then
      ddsdde = transpose(row_major)
    end if
  end function rve_update_f

  ! The detailed message of the last failed call on this thread ("" after a success).
  function rve_last_error_f() result(msg)
    character(len=:, kind=c_char), allocatable :: msg
    character(kind=c_char) :: probe(1)
    character(kind=c_char), allocatable :: buf(:)
    integer(c_size_t) :: n, got
    integer :: i
    n = rve_last_error(probe, 0_c_size_t)
    allocate (buf(n + 1))
    got = rve_last_error(buf, n + 1)
    n = min(n, got)
    allocate (character(len=int(n), kind=c_char) :: msg)
    do i = 1, int(n)
      msg(i:i) = buf(i)
    end do
  end function rve_last_error_f

  ! The static description of a status code.
  function rve_status_message_f(code) result(msg)
    integer(c_int32_t), intent(in) :: code
    character(len=:, kind=c_char), allocatable :: msg
    msg = c_string(rve_status_message(code))
  end function rve_status_message_f

  ! The library version "major.minor.patch".
  function rve_version_f() result(version)
    character(len=:, kind=c_char), allocatable :: version
    version = c_string(rve_version())
  end function rve_version_f

  ! Copies a static NUL-terminated C string (at most 4096 characters are read).
  function c_string(p) result(s)
    type(c_ptr), intent(in) :: p
    character(len=:, kind=c_char), allocatable :: s
    integer, parameter :: max_len = 4096
    character(kind=c_char), pointer :: chars(:)
    integer :: n, i
    if (.not. c_associated(p)) then
      s = ""
      return
    end if
    call c_f_pointer(p, chars, [max_len])
    n = 0
    do while (n < max_len)
      if (chars(n + 1) == c_null_char) exit
      n = n + 1
    end do
    allocate (character(len=n, kind=c_char) :: s)
    do i = 1, n
      s(i:i) = chars(i)
    end do
  end function c_string

end module rve

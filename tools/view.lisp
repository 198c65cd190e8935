;;;; tools/view.lisp -- record a standard scene and write its viewer (make view SCENE=basin), or
;;;; a world of one's own (make view FILE=my-world.lisp).
;;;; Environment: SCENE (the name of a scene of the page, default basin), EVERY (steps a frame,
;;;; default 2), VIEW (the file to write, default report/view-SCENE.html, or report/view-NAME.html
;;;; for FILE=NAME.lisp).  With FILE, the file's forms are read and evaluated in order in the
;;;; package luv-physics-user (which uses CL and LUV-PHYSICS); the value of its last form is the
;;;; world, recorded for STEPS steps (default 240); BOUNDS="x0 y0 z0 x1 y1 z1" is the box whose
;;;; terrain is drawn (default: around the bodies).

(load (merge-pathnames "boot.lisp" *load-truename*))

(in-package #:cl-user)

(when (luv-load-systems "luv-physics/workshop")
  (sb-ext:exit :code 2))

(defun physics (name) (find-symbol name '#:luv-physics))

(defun env (name default)
  "The environment variable NAME, or DEFAULT when it is unset or empty."
  (let ((value (sb-ext:posix-getenv name)))
    (if (and value (plusp (length value))) value default)))

(defun view-world-file (file)
  "Evaluate FILE's forms in luv-physics-user, record the world its last form returns and write
its viewer, as the environment says."
  (let* ((*package* (or (find-package '#:luv-physics-user)
                        (make-package '#:luv-physics-user :use '(#:cl #:luv-physics))))
         (steps (parse-integer (env "STEPS" "240")))
         (every (parse-integer (env "EVERY" "2")))
         (bounds (let ((text (env "BOUNDS" nil)))
                   (and text
                        (with-input-from-string (in text)
                          (loop for v = (read in nil) while v collect v)))))
         (out (env "VIEW" (format nil "report/view-~A.html" (pathname-name file))))
         (world (with-open-file (in file)
                  (let ((*load-truename* (truename file)) (value nil))
                    (loop for form = (read in nil in) until (eq form in)
                          do (setf value (eval form)))
                    value))))
    (unless (typep world (physics "PHYSICS-WORLD"))
      (format *error-output* "view: the last form of ~A returned ~S, not a world~%" file world)
      (sb-ext:exit :code 1))
    (ensure-directories-exist out)
    (let ((start (get-internal-real-time)))
      (funcall (physics "WRITE-WORLD-VIEWER") world out :steps steps :every every :bounds bounds
               :title (pathname-name file))
      (format t "~&view: ~A, ~D steps, a frame every ~D: written in ~,2F s: ~A, ~,1F MB~%"
              file steps every (/ (- (get-internal-real-time) start) internal-time-units-per-second)
              out (/ (with-open-file (s out) (file-length s)) 1d6))
      (format t "~&view: open file://~A in a browser~%" (namestring (truename out))))
    (sb-ext:exit :code 0)))

(let ((file (sb-ext:posix-getenv "FILE")))
  (when (and file (plusp (length file)))
    (handler-case (view-world-file file)
      (error (e)
        (format *error-output* "view: ~A~%" e)
        (sb-ext:exit :code 1)))))

(let* ((name (intern (string-upcase (or (sb-ext:posix-getenv "SCENE") "basin")) :keyword))
       (scene (handler-case (funcall (physics "FIND-PHYSICS-SCENE") name)
                (error (e)
                  (format *error-output* "view: ~A~%" e)
                  (sb-ext:exit :code 1))))
       (every (parse-integer (or (sb-ext:posix-getenv "EVERY") "2")))
       (out (or (sb-ext:posix-getenv "VIEW") (format nil "report/view-~(~A~).html" name))))
  (ensure-directories-exist out)
  (sb-ext:gc :full t)
  (let ((start (get-internal-real-time)))
    (multiple-value-bind (world recording)
        (funcall (physics "RUN-PHYSICS-SCENE") name :record t :every every)
      (declare (ignore world))
      (let ((recorded (get-internal-real-time)))
        (funcall (physics "WRITE-PHYSICS-VIEWER") recording out
                 :title (format nil "~(~A~): ~A" name (funcall (physics "PHYSICS-SCENE-TEXT") scene)))
        (let ((written (get-internal-real-time))
              (frames (funcall (physics "PHYSICS-RECORDING-FRAME-COUNT") recording)))
          (format t "~&view: ~(~A~), ~D s at 60 Hz, a frame every ~D steps: ~D frames~%"
                  name (funcall (physics "PHYSICS-SCENE-SECONDS") scene) every frames)
          (format t "~&view: run and recorded in ~,2F s, written in ~,2F s: ~A, ~,1F MB~%"
                  (/ (- recorded start) internal-time-units-per-second)
                  (/ (- written recorded) internal-time-units-per-second)
                  out (/ (with-open-file (s out) (file-length s)) 1d6))
          (format t "~&view: open file://~A in a browser~%" (namestring (truename out))))))))
